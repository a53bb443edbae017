#include "cli_options.h"

#include <sys/stat.h>

#include <filesystem>
#include <regex>
#include <set>

#include <defocus/shot/option_value.h>

namespace defocus {

using OIIO::ArgParse;
using OIIO::cspan;

std::string overwritten_input(const std::vector<std::string>& read,
                              const std::vector<std::string>& written)
{
    std::set<std::pair<dev_t, ino_t>> inputs;
    struct stat st {};
    for (const std::string& file : read)
        if (::stat(file.c_str(), &st) == 0)
            inputs.emplace(st.st_dev, st.st_ino);
    for (const std::string& file : written)
        if (!file.empty() && ::stat(file.c_str(), &st) == 0
            && inputs.count({ st.st_dev, st.st_ino }))
            return file;
    return "";
}

bool same_path(const std::string& a, const std::string& b)
{
    std::error_code ec_a, ec_b;
    const std::filesystem::path pa = std::filesystem::weakly_canonical(a, ec_a);
    const std::filesystem::path pb = std::filesystem::weakly_canonical(b, ec_b);
    return ec_a || ec_b ? a == b : pa == pb;
}

int parse_arguments(ArgParse& ap, int argc, const char* argv[])
{
    static const std::regex option_value("(--[a-z][a-z0-9-]*)=(.*)");
    std::vector<std::string> args;
    std::cmatch m;
    for (int i = 0; i < argc; ++i) {
        if (i > 0 && std::regex_match(argv[i], m, option_value)) {
            args.push_back(m[1]);
            args.push_back(m[2]);
        } else {
            args.emplace_back(argv[i]);
        }
    }
    std::vector<const char*> pointers;
    for (const std::string& a : args)
        pointers.push_back(a.c_str());
    return ap.parse_args(int(pointers.size()), pointers.data());
}

std::function<void(cspan<const char*>)> ShotArguments::store_into(std::string& into)
{
    return [this, &into](cspan<const char*> argv) {
        m_given.push_back({ argv[0], "", argv[1] });
        into = argv[1];
    };
}

void ShotArguments::add(ArgParse& ap, const char* spec, const char* setting, const char* help,
                        const char* value)
{
    ap.arg(spec).help(help).action([this, setting, value](cspan<const char*> argv) {
        m_given.push_back({ argv[0], setting, value ? value : argv[1] });
    });
}

void ShotArguments::add_camera(ArgParse& ap)
{
    ap.separator("Camera (DIST, N and MM take keyframes FRAME:VALUE,... for a focus pull):");
    add(ap, "--focus DIST", "focus",
        "Focus distance in metres, e.g. 3 or 1001:3,1040:1.2 (required, or --focus-at)");
    add(ap, "--focus-at X,Y", "focus-at",
        "Focus on what is seen at display-window pixel X,Y: the median depth of the "
        "front-most opaque surface over 5x5 pixels; keyframes F:X,Y,F:X,Y...");
    add(ap, "--focal MM", "focal", "Focal length in mm (default: 50)");
    add(ap, "--fstop N", "fstop", "Aperture f-number (default: 2.8)");
    add(ap, "--sensor MM", "sensor",
        "Horizontal filmback width in mm, spanning the display window (default: 36)");
    add(ap, "--lens MODEL", "lens",
        "thin: render cameras, no breathing (default); optical: Potmesil & Chakravarty");
    add(ap, "--max-blur PX", "max-blur",
        "Largest CoC diameter in pixels; larger blur is clamped (default: 512)");
}

void ShotArguments::add_scene(ArgParse& ap)
{
    ap.separator("Scene:");
    add(ap, "--view NAME", "view",
        "View of a multi-view EXR (default: the first part's view)");
    add(ap, "--layer NAME", "layer",
        "Channel prefix of colour and depth, e.g. 'beauty' for beauty.R..beauty.Z, or "
        "Blender's view layer name (default: plain R,G,B,A,Z or the file's only "
        "prefixed set)");
    add(ap, "--depth FILE|CHANNEL", "depth",
        "Depth for a render without Z, or instead of its Z: a channel of the input by name, "
        "or a depth image (its Z or only channel; a frame pattern for sequences)");
    add(ap, "--depth-scale S", "depth-scale",
        "Metres per depth unit of the input's Z, e.g. 0.01 for centimetres (default: 1; "
        "--focus stays in metres)");
    add(ap, "--layers N", "layers",
        "Depth layers to cut deep and flat inputs into, spaced evenly in CoC (default: "
        "0 = automatic: boundaries in the gaps between objects, at most 24 px of CoC "
        "per layer)");
}

void ShotArguments::add_input_color(ArgParse& ap)
{
    add(ap, "--colorconfig FILE", "colorconfig",
        "OCIO config (default: $OCIO, else the config shipped with defocus)");
    add(ap, "--iscolorspace NAME", "iscolorspace",
        "Colour space of the input (default: the file's oiio:ColorSpace if the config has "
        "it, else linear)");
}

void ShotArguments::add_threads(ArgParse& ap)
{
    ap.arg("--threads N").help("Worker threads (default: 0 = all cores)")
        .action(store_into(m_threads));
}

bool ShotArguments::apply(Shot& shot, std::string& error) const
{
    for (size_t i = 0; i < m_given.size(); ++i)
        for (size_t j = i + 1; j < m_given.size(); ++j) {
            const Given &a = m_given[i], &b = m_given[j];
            const bool same = a.setting.empty() ? a.option == b.option : a.setting == b.setting;
            if (!same || a.value == b.value)
                continue;
            error = a.option == b.option
                        ? OIIO::Strutil::fmt::format("{} given twice ('{}' and '{}'): give it once",
                                                     a.option, a.value, b.value)
                        : OIIO::Strutil::fmt::format("{} and {} contradict each other: give one",
                                                     a.option, b.option);
            return false;
        }
    for (const Given& g : m_given)
        if (!g.setting.empty()
            && !set_shot_setting(shot, g.setting, g.value, error,
                                 g.setting == "pixel-type" ? "-d" : ""))
            return false;
    // Options that shape only a polygon do nothing to other apertures.
    for (const Given& g : m_given)
        if ((g.setting == "blades" || g.setting == "roundness" || g.setting == "rotation")
            && shot.spread.aperture.shape != ApertureShape::Polygon) {
            error = OIIO::Strutil::fmt::format("{} applies only to --aperture polygon (the "
                                               "aperture is {})",
                                               g.option,
                                               aperture_shape_name(shot.spread.aperture.shape));
            return false;
        }
    return true;
}

bool ShotArguments::threads(int& threads, std::string& error) const
{
    return parse_whole_number("--threads", m_threads, 0, 1024, threads, error);
}

}  // namespace defocus
