#include <defocus/shot/setting_words.h>

#include <OpenImageIO/strutil.h>

#include <defocus/shot/shot.h>

namespace defocus {

namespace Strutil = OIIO::Strutil;

namespace {

// A mention is "\x1f" NAME ["\x1e" VALUE] "\x1f": control characters, which
// no setting name or value written by the library holds.
constexpr char mention_mark = '\x1f';
constexpr char value_mark   = '\x1e';

/// "X,Y", "DIST": capitals, and no small letter.
bool is_placeholder(const std::string& value)
{
    return Strutil::upper(value) == value && Strutil::lower(value) != value;
}

std::string command_line_words(const ShotSetting& s, const std::string& value)
{
    for (const SettingSwitch& on : s.switches)
        if (value == on.value)
            return on.flag;
    if (!s.option) {
        std::vector<std::string> flags;
        for (const SettingSwitch& on : s.switches)
            flags.emplace_back(on.flag);
        return Strutil::join(flags, " or ");
    }
    const std::string flag = Strutil::splits(s.option, " ")[0];
    return value.empty() ? flag : flag + " " + value;
}

std::string python_words(const ShotSetting& s, const std::string& value)
{
    std::string words = Strutil::replace(s.name, "-", "_", true);
    if (value.empty())
        return words;
    Shot scratch;
    std::string ignored;
    const bool literal =
        !is_placeholder(value) && set_shot_setting(scratch, s.name, value, ignored);
    if (!literal)
        return words + "=" + value;
    if (s.kind == ShotValueKind::Point)
        return words + "=(" + Strutil::replace(value, ",", ", ", true) + ")";
    if (s.kind == ShotValueKind::Switch)
        return words + "=" + (value == "on" ? "True" : "False");
    return words + "=" + (Strutil::string_is<double>(value) ? value : "\"" + value + "\"");
}

std::string scene_file_words(const ShotSetting& s, const std::string& value)
{
    std::string words = std::string(s.section) + "." + s.key;
    if (value.empty())
        return words;
    if (is_placeholder(value) || Strutil::string_is<double>(value))
        return words + " " + value;
    if (s.kind == ShotValueKind::Point)
        return words + " [" + Strutil::replace(value, ",", ", ", true) + "]";
    return words + " \"" + value + "\"";
}

}  // namespace

std::string mention(const std::string& name, const std::string& value)
{
    std::string text = mention_mark + name;
    if (!value.empty())
        text += value_mark + Strutil::replace(value, std::string(1, mention_mark), "?", true);
    return text + mention_mark;
}

std::string setting_words(const std::string& name, const std::string& value, SettingForm form)
{
    const ShotSetting* s = find_shot_setting(name);
    if (!s)
        return value.empty() ? name : name + " " + value;
    switch (form) {
    case SettingForm::Python: return python_words(*s, value);
    case SettingForm::SceneFile: return scene_file_words(*s, value);
    default: return command_line_words(*s, value);
    }
}

std::string in_words(const std::string& message, SettingForm form)
{
    std::string out;
    size_t at = 0;
    for (size_t open; (open = message.find(mention_mark, at)) != std::string::npos;) {
        const size_t close = message.find(mention_mark, open + 1);
        if (close == std::string::npos)
            break;
        const std::string inner = message.substr(open + 1, close - open - 1);
        const size_t split      = inner.find(value_mark);
        out.append(message, at, open - at);
        out += setting_words(inner.substr(0, split),
                             split == std::string::npos ? "" : inner.substr(split + 1), form);
        at = close + 1;
    }
    return out.append(message, at, std::string::npos);
}

}  // namespace defocus
