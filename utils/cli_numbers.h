// Strict parsing of numeric command-line values.
#pragma once

#include <string>

namespace defocus {

/// Parses all of `text` as a finite number in [lo, hi] into `value`. On
/// failure sets `error` to a message naming `option` and returns false.
bool parse_number(const char* option, const std::string& text, double lo,
                  double hi, double& value, std::string& error);

}  // namespace defocus
