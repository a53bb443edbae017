// Settings named in the library's messages. The library names a setting by
// its setting name, with a value or a placeholder; each front end words it
// as its users write it: the command line's "--focus-at 10,20", Python's
// "focus_at=(10, 20)", a .dof file's "camera.focus_at [10, 20]".
#pragma once

#include <string>

namespace defocus {

/// How a front end writes settings.
enum class SettingForm {
    CommandLine,  ///< "--fstop 2", "-d half", "--crop"
    Python,       ///< "fstop=2", 'aperture="polygon"'
    SceneFile,    ///< "camera.fstop 2", 'aperture.shape "polygon"'
};

/// The setting `name` (see shot_settings()) in a library message, with
/// `value`: a value, a placeholder in capitals ("X,Y"), or "" for the
/// setting alone. in_words() words it for a front end.
std::string mention(const std::string& name, const std::string& value = "");

/// The setting `name` with `value` (or alone, for ""), as `form` writes it.
std::string setting_words(const std::string& name, const std::string& value, SettingForm form);

/// `message` with each setting it mentions worded in `form`.
std::string in_words(const std::string& message, SettingForm form);

}  // namespace defocus
