#include "cli_numbers.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include <OpenImageIO/strutil.h>

namespace defocus {

bool parse_number(const char* option, const std::string& text, double lo,
                  double hi, double& value, std::string& error)
{
    const char* begin = text.c_str();
    char* end         = nullptr;
    errno             = 0;
    const double v    = std::strtod(begin, &end);
    if (text.empty() || end == begin || *end != '\0' || errno == ERANGE
        || !std::isfinite(v)) {
        error = OIIO::Strutil::fmt::format("{}: '{}' is not a number", option, text);
        return false;
    }
    if (v < lo || v > hi) {
        error = OIIO::Strutil::fmt::format("{}: {} is out of range [{}, {}]",
                                           option, text, lo, hi);
        return false;
    }
    value = v;
    return true;
}

}  // namespace defocus
