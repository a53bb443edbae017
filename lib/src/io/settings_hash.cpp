#include <defocus/io/settings_hash.h>

#include <filesystem>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/hash.h>
#include <OpenImageIO/strutil.h>

#include <defocus/io/frames.h>
#include <defocus/version.h>

namespace defocus {

namespace {

std::string absolute_path(const std::string& path)
{
    if (path.empty())
        return path;
    std::error_code ec;
    const std::filesystem::path absolute = std::filesystem::absolute(path, ec);
    return ec ? path : absolute.lexically_normal().string();
}

}  // namespace

std::string settings_hash(const Shot& shot, int frame)
{
    // One line per value, in the settings table's order: a canonical text.
    // Another version of defocus may render the same settings differently.
    std::string text = OIIO::Strutil::fmt::format("version={}\nframe={}\n", version(), frame);
    // A frame held from another (its own inputs missing) is rendered again
    // once its inputs are there.
    if (const int source = source_frame(shot, frame); source != frame)
        text += OIIO::Strutil::fmt::format("read from frame={}\n", source);
    for (const std::string& input : shot.inputs)
        text += "input=" + absolute_path(input) + "\n";
    for (const ShotSetting& s : shot_settings()) {
        const std::string name = s.name;
        if (name == "frames" || name == "memory-limit")
            continue;
        std::string value = shot_setting(shot, name);
        if (s.kind == ShotValueKind::Path
            || (s.kind == ShotValueKind::FileOrName && OIIO::Filesystem::exists(value)))
            value = absolute_path(value);
        text += name + "=" + value + "\n";
    }
    return OIIO::Strutil::fmt::format("{:016x}", OIIO::farmhash::Fingerprint64(text));
}

}  // namespace defocus
