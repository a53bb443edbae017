// Error messages as the tools print them: one line, of bounded length.
#pragma once

#include <cstddef>
#include <string>

#include <defocus/shot/setting_words.h>

namespace defocus {

/// `message`, its settings worded in `form`, as one line of at most about
/// `limit` characters: control characters (a newline in a JSON key, a file
/// name) written as \n, \t, \xHH, and the middle of an overlong message
/// (a 100 MB key) cut to " ... ", so that the start (the file) and the end
/// (the problem) stay.
std::string error_line(const std::string& message, SettingForm form, size_t limit = 1000);

/// "file: message", unless `message` already begins with "file: " (an
/// error passed up through a nested scene file names it once).
std::string error_about(const std::string& file, const std::string& message);

}  // namespace defocus
