// Writes the manual's settings reference (Markdown) from the settings table,
// the one source of the command line, .dof files, Python and the plugin, so
// that a setting added to the table appears in the manual with no other edit.
#include <cstdio>
#include <string>

#include <OpenImageIO/strutil.h>

#include <defocus/shot/shot.h>

namespace {

using namespace defocus;
using OIIO::Strutil::fmt::format;

const char* group_title(OptionGroup group)
{
    switch (group) {
    case OptionGroup::Sequences: return "Sequences";
    case OptionGroup::Camera: return "Camera";
    case OptionGroup::Aperture: return "Aperture";
    case OptionGroup::Scene: return "Scene";
    case OptionGroup::InputColor: return "Input colour";
    case OptionGroup::OutputColor: return "Output colour";
    case OptionGroup::Output: return "Output";
    }
    return "";
}

/// How a .dof file writes the value (ShotValueKind's meaning).
const char* dof_value(ShotValueKind kind)
{
    switch (kind) {
    case ShotValueKind::Number: return "a number";
    case ShotValueKind::Keyframes: return "a number, or keyframes `{\"FRAME\": number, ...}`";
    case ShotValueKind::Point: return "`[x, y]`, or keyframes `{\"FRAME\": [x, y], ...}`";
    case ShotValueKind::Text: return "a string";
    case ShotValueKind::Path: return "a file name, relative to the `.dof` file";
    case ShotValueKind::FileOrName:
        return "a string: a file relative to the `.dof` file when one is there, else a name";
    case ShotValueKind::Switch: return "`\"on\"` or `\"off\"` (or `true`, `false`)";
    }
    return "";
}

/// Help text as Markdown: its '*' and '<' are text, not emphasis or HTML.
std::string paragraph(const char* text)
{
    std::string markdown = OIIO::Strutil::replace(text, "*", "\\*", true);
    return OIIO::Strutil::replace(markdown, "<", "&lt;", true);
}

void write_setting(const ShotSetting& s)
{
    const std::string python = OIIO::Strutil::replace(s.name, "-", "_", true);
    std::printf("### `%s`\n\n%s\n\n", s.name, paragraph(s.help).c_str());
    if (s.option)
        std::printf("- command line: `%s`\n", s.option);
    for (const SettingSwitch& sw : s.switches)
        std::printf("- command line: `%s` (sets `%s`): %s\n", sw.flag, sw.value,
                    paragraph(sw.help).c_str());
    std::printf("- `.dof`: `%s.%s`, %s\n", s.section, s.key, dof_value(s.kind));
    std::printf("- Python: `Shot(%s=...)`\n", python.c_str());
    std::printf("- plugin hint: `--iconfig dof:%s VALUE`\n\n", s.name);
}

/// The `.dof` keys, one row each, for the format's page.
void write_dof_keys()
{
    std::printf("| key | value | command line |\n|---|---|---|\n");
    for (const ShotSetting& s : shot_settings()) {
        std::string flags = s.option ? format("`{}`", s.option) : "";
        for (const SettingSwitch& sw : s.switches)
            flags += format("{}`{}` ({})", flags.empty() ? "" : ", ", sw.flag, sw.value);
        std::printf("| [`%s.%s`](settings.md#%s) | %s | %s |\n", s.section, s.key, s.name,
                    dof_value(s.kind), OIIO::Strutil::replace(flags, "|", "\\|", true).c_str());
    }
}

void write_settings()
{
    std::printf("# Settings\n\n"
                "Every setting of a shot, as the command line, `.dof` scene files, Python "
                "and the OpenImageIO plugin name it. This page is generated from the "
                "settings table (`lib/src/shot/settings_table.cpp`), as `defocus --help` "
                "and the man pages are. Options of the tools themselves (`-o`, `-v`, "
                "`--threads`, ...) are in [the commands' help](commands.md).\n\n");
    for (OptionGroup group : { OptionGroup::Sequences, OptionGroup::Camera,
                               OptionGroup::Aperture, OptionGroup::Scene,
                               OptionGroup::InputColor, OptionGroup::OutputColor,
                               OptionGroup::Output }) {
        std::printf("## %s\n\n", group_title(group));
        for (const ShotSetting& s : shot_settings())
            if (s.group == group)
                write_setting(s);
    }
}

}  // namespace

/// settings_reference: the settings page; settings_reference dof-keys: the
/// table of .dof keys.
int main(int argc, char** argv)
{
    if (argc > 1 && std::string(argv[1]) == "dof-keys")
        write_dof_keys();
    else
        write_settings();
    return 0;
}
