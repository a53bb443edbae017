#include "python_errors.h"

#include <defocus/error_line.h>

namespace defocus_python {

Error::Error(const std::string& message)
    : std::runtime_error(defocus::error_line(message, defocus::SettingForm::Python))
{
}

void check(bool ok, const std::string& error)
{
    if (!ok)
        throw Error(error);
}

}  // namespace defocus_python
