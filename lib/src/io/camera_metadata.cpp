#include <defocus/io/camera_metadata.h>

#include <cmath>
#include <cstdlib>
#include <initializer_list>

#include <Imath/ImathMatrix.h>
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

/// f/s from the camera's projection: with row vectors (Imath's and
/// OpenEXR's convention), camera space maps to NDC by
/// worldToCamera⁻¹ · worldToNDC, and a perspective camera sends (x, y, z)
/// to x_ndc = (f/s) x / z + 1/2, NDC spanning the display window's width.
HeaderValue projection_ratio(const OIIO::ImageSpec& spec)
{
    const OIIO::ParamValue* to_camera = spec.find_attribute("worldToCamera", OIIO::TypeMatrix44);
    const OIIO::ParamValue* to_ndc = spec.find_attribute("worldToNDC", OIIO::TypeMatrix44);
    if (!to_camera || !to_ndc)
        return {};
    const Imath::M44f w2c = *static_cast<const Imath::M44f*>(to_camera->data());
    const Imath::M44f w2n = *static_cast<const Imath::M44f*>(to_ndc->data());
    if (std::abs(w2c.determinant()) < 1e-12f)
        return {};
    const Imath::M44f c2n = w2c.inverse() * w2n;
    if (std::abs(c2n[2][3]) < 1e-6f)  // orthographic: no field of view
        return {};
    const double ratio = std::abs(double(c2n[0][0]) / double(c2n[2][3]));
    if (!std::isfinite(ratio) || !(ratio > 0.0))
        return {};
    return { ratio, "worldToNDC" };
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
                                       { "cameraFocalLength", 1.0 },
                                       { "unreal/camera/FinalImage/focalLength", 1.0 },
                                       { "unreal/camera/*/focalLength", 1.0 } });
    c.sensor_width_mm = lookup(spec, { { "CameraFilmApertureHorizontal", 1.0 },
                                       { "cameraAperture", 1.0 },
                                       { "unreal/camera/FinalImage/sensorWidth", 1.0 },
                                       { "unreal/camera/*/sensorWidth", 1.0 } });
    c.focal_over_filmback = projection_ratio(spec);
    return c;
}

double header_pixel_aspect(const OIIO::ImageSpec& spec)
{
    const float aspect = spec.get_float_attribute("PixelAspectRatio", 1.0f);
    // Beyond 1/100..100 a header is broken, not anamorphic.
    return std::isfinite(aspect) && aspect >= 0.01f && aspect <= 100.0f ? aspect : 1.0;
}

}  // namespace defocus
