#include <defocus/shot/camera_metadata.h>

#include <cmath>
#include <cstdlib>
#include <initializer_list>

#include <OpenImageIO/strutil.h>

namespace defocus {

using OIIO::Strutil::ends_with;
using OIIO::Strutil::starts_with;

namespace {

/// An attribute that holds a camera value, and the factor to defocus's
/// unit. A '*' stands for one path component: Unreal writes
/// "unreal/camera/PASS/NAME" for each render pass.
struct Source {
    const char* name;
    double to_unit;
};

bool matches(const std::string& name, const std::string& pattern)
{
    const size_t star = pattern.find('*');
    if (star == std::string::npos)
        return name == pattern;
    const std::string head = pattern.substr(0, star), tail = pattern.substr(star + 1);
    return name.size() > head.size() + tail.size() && starts_with(name, head)
           && ends_with(name, tail)
           && name.find('/', head.size()) == name.size() - tail.size();
}

/// A number from a float, int or string attribute (Unreal writes strings).
bool number(const OIIO::ParamValue& p, double& value)
{
    const OIIO::TypeDesc t = p.type();
    if (t == OIIO::TypeString) {
        const std::string text = p.get_string();
        char* end = nullptr;
        value = std::strtod(text.c_str(), &end);
        return end != text.c_str() && *end == '\0';
    }
    if (t.aggregate != OIIO::TypeDesc::SCALAR || t.arraylen != 0
        || t.basetype == OIIO::TypeDesc::STRING || t.basetype == OIIO::TypeDesc::PTR)
        return false;
    value = p.get_float();
    return true;
}

/// The first source, in order, that the header has with a usable value.
HeaderValue lookup(const OIIO::ImageSpec& spec, std::initializer_list<Source> sources)
{
    for (const Source& s : sources)
        for (const OIIO::ParamValue& p : spec.extra_attribs) {
            double value = 0.0;
            if (!matches(p.name().string(), s.name) || !number(p, value))
                continue;
            value *= s.to_unit;
            if (std::isfinite(value) && value > 0.0)
                return { value, p.name().string() };
        }
    return {};
}

}  // namespace

HeaderCamera camera_from_header(const OIIO::ImageSpec& spec)
{
    HeaderCamera c;
    // OpenEXR's standard attributes: `focus` in metres, `aperture` in
    // f-stops (OpenImageIO reads `aperture` as FNumber). Unreal's distances
    // are in centimetres.
    c.focus_distance = lookup(spec, { { "focus", 1.0 },
                                      { "unreal/camera/FinalImage/focalDistance", 0.01 },
                                      { "unreal/camera/*/focalDistance", 0.01 } });
    c.fstop = lookup(spec, { { "FNumber", 1.0 },
                             { "aperture", 1.0 },
                             { "unreal/camera/FinalImage/fstop", 1.0 },
                             { "unreal/camera/*/fstop", 1.0 } });
    c.focal_length_mm = lookup(spec, { { "CameraFocalLength", 1.0 },
                                       { "unreal/camera/FinalImage/focalLength", 1.0 },
                                       { "unreal/camera/*/focalLength", 1.0 } });
    c.sensor_width_mm = lookup(spec, { { "CameraFilmApertureHorizontal", 1.0 },
                                       { "unreal/camera/FinalImage/sensorWidth", 1.0 },
                                       { "unreal/camera/*/sensorWidth", 1.0 } });
    return c;
}

}  // namespace defocus
