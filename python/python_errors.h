// The library's errors as Python sees them: defocus.Error, its one-line
// message naming each setting by its Python keyword.
#pragma once

#include <stdexcept>
#include <string>

namespace defocus_python {

/// Raised as defocus.Error, with the one-line message the CLI prints, the
/// settings named as Python keywords ("focus_at=(10, 20)").
struct Error : std::runtime_error {
    explicit Error(const std::string& message);
};

/// Raises Error(error) unless ok.
void check(bool ok, const std::string& error);

}  // namespace defocus_python
