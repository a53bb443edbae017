// Strict parsing of option values, shared by the command line, .dof scene
// files and plugin hints.
#pragma once

#include <cstddef>
#include <string>

namespace defocus {

/// Parses all of `text` as a finite number in [lo, hi] into `value`. On
/// failure sets `error` to a message naming `option` and returns false.
bool parse_number(const std::string& option, const std::string& text, double lo,
                  double hi, double& value, std::string& error);

/// parse_number() for whole numbers.
bool parse_whole_number(const std::string& option, const std::string& text, double lo,
                        double hi, int& value, std::string& error);

}  // namespace defocus
