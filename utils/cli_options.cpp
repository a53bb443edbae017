#include "cli_options.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include <OpenImageIO/strutil.h>

namespace defocus {

using OIIO::ArgParse;
using OIIO::cspan;

bool parse_number(const char* option, const std::string& text, double lo,
                  double hi, double& value, std::string& error)
{
    const char* begin = text.c_str();
    char* end         = nullptr;
    errno             = 0;
    const double v    = std::strtod(begin, &end);
    if (text.empty() || end == begin || *end != '\0' || errno == ERANGE
        || !std::isfinite(v)) {
        error = OIIO::Strutil::fmt::format("{}: '{}' is not a number", option, text);
        return false;
    }
    if (v < lo || v > hi) {
        error = OIIO::Strutil::fmt::format("{}: {} is out of range [{}, {}]",
                                           option, text, lo, hi);
        return false;
    }
    value = v;
    return true;
}

std::function<void(cspan<const char*>)> store_into(std::string& into)
{
    return [&into](cspan<const char*> argv) { into = argv[1]; };
}

namespace {

bool parse_count(const char* option, const std::string& text, int hi, int& value,
                 std::string& error)
{
    double v = 0;
    if (!parse_number(option, text, 0, hi, v, error))
        return false;
    if (v != std::floor(v)) {
        error = OIIO::Strutil::fmt::format("{}: {} is not a whole number", option, text);
        return false;
    }
    value = int(v);
    return true;
}

}  // namespace

void SceneArguments::add_camera(ArgParse& ap)
{
    ap.separator("Camera:");
    ap.arg("--focal MM").help("Focal length in mm (default: 50)").action(store_into(m_focal));
    ap.arg("--fstop N").help("Aperture f-number (default: 2.8)").action(store_into(m_fstop));
    ap.arg("--focus DIST").help("Focus distance in metres (required)").action(store_into(m_focus));
    ap.arg("--sensor MM")
        .help("Horizontal filmback width in mm, spanning the display window "
              "(default: 36)")
        .action(store_into(m_sensor));
    ap.arg("--lens MODEL")
        .help("thin: render cameras, no breathing (default); optical: "
              "Potmesil & Chakravarty")
        .action(store_into(m_lens));
    ap.arg("--max-blur PX")
        .help("Largest CoC diameter in pixels; larger blur is clamped "
              "(default: 512)")
        .action(store_into(m_max_blur));
}

void SceneArguments::add_scene(ArgParse& ap)
{
    ap.separator("Scene:");
    ap.arg("--view NAME")
        .help("View of a multi-view EXR (default: the first part's view)")
        .action(store_into(m_view));
    ap.arg("--layer NAME")
        .help("Channel prefix of colour and depth, e.g. 'beauty' for beauty.R.."
              "beauty.Z, or Blender's view layer name (default: plain R,G,B,A,Z or "
              "the file's only prefixed set)")
        .action(store_into(m_layer));
    ap.arg("--layers N")
        .help("Depth layers to cut deep and flat inputs into, spaced evenly in "
              "CoC (default: 0 = automatic: boundaries in the gaps between "
              "objects, at most 24 px of CoC per layer)")
        .action(store_into(m_layers));
}

void SceneArguments::add_threads(ArgParse& ap)
{
    ap.arg("--threads N").help("Worker threads (default: 0 = all cores)")
        .action(store_into(m_threads));
}

bool SceneArguments::resolve(SceneSettings& s, std::string& error) const
{
    Camera& cam = s.camera;
    if (!parse_number("--focal", m_focal, 1e-3, 1e5, cam.focal_length_mm, error)
        || !parse_number("--fstop", m_fstop, 0.1, 1e4, cam.fstop, error)
        || !parse_number("--sensor", m_sensor, 1e-3, 1e4, cam.sensor_width_mm, error)
        || !parse_number("--max-blur", m_max_blur, 0.0, 1e5, cam.max_blur_px, error)
        || !parse_count("--threads", m_threads, 1024, s.threads, error)
        || !parse_count("--layers", m_layers, 256, s.layering.layers, error))
        return false;
    if (m_focus.empty()) {
        error = "--focus DIST is required: the distance of the plane in focus";
        return false;
    }
    if (!parse_number("--focus", m_focus, 1e-6, 1e30, cam.focus_distance, error))
        return false;
    if (!parse_lens_model(m_lens, cam.lens)) {
        error = "--lens: unknown model '" + m_lens + "' (choose thin or optical)";
        return false;
    }
    error = validate(cam);
    if (!error.empty())
        return false;
    s.read.view  = m_view;
    s.read.layer = m_layer;
    return true;
}

}  // namespace defocus
