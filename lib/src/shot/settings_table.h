// The table of a shot's settings: each setting's names, help, and how its
// value is read from text and written back.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <defocus/shot/shot.h>

namespace defocus {

/// A setting and its value's parser and printer. The parser takes the
/// label that names the setting in its errors.
struct SettingRule {
    using Setter = std::function<bool(Shot&, const std::string& label,
                                      const std::string& value, std::string& error)>;
    using Getter = std::function<std::string(const Shot&)>;

    ShotSetting setting;
    Setter set;
    Getter get;
};

/// Every setting, in the order of shot_settings().
const std::vector<SettingRule>& setting_rules();

}  // namespace defocus
