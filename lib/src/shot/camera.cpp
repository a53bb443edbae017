#include <defocus/shot/camera.h>

#include <algorithm>
#include <cmath>

#include <OpenImageIO/strutil.h>

#include <defocus/shot/option_value.h>

namespace defocus {

CircleOfConfusion::CircleOfConfusion(const Camera& camera, int display_width)
    : m_lens(camera.lens)
    , m_focus(camera.focus_distance)
    , m_inv_focus(1.0 / camera.focus_distance)
    , m_max_diameter(camera.max_blur_px)
{
    // f and s only appear as f/s and f (in scene units): focal length in
    // mm, converted to metres, the unit of depth.
    const double f = camera.focal_length_mm * 1e-3;
    const double f_over_s = camera.focal_length_mm / camera.sensor_width_mm;
    m_scale = f * f_over_s / camera.fstop * display_width;
    if (m_lens == LensModel::Optical)
        m_scale *= m_focus / (m_focus - f);
}

double CircleOfConfusion::diameter(double z) const
{
    const double inv_z = std::isinf(z) ? 0.0 : 1.0 / z;
    // Thin lens (the paper's eq. 1 with the image plane fixed):
    //   c = f^2 / (N s) * W * (1/z_f - 1/z).
    // Potmesil & Chakravarty: f^2 |z - z_f| / (N z (z_f - f)) * W/s, which
    // is the same expression times z_f / (z_f - f), folded into m_scale.
    const double c = m_scale * (m_inv_focus - inv_z);
    return std::clamp(c, -m_max_diameter, m_max_diameter);
}

double CircleOfConfusion::depth_at(double c) const
{
    const double inv_z = m_inv_focus - c / m_scale;
    return inv_z > 0.0 ? 1.0 / inv_z : INFINITY;
}

bool parse_lens_model(const std::string& name, LensModel& lens)
{
    return parse_name(name, { LensModel::ThinLens, LensModel::Optical }, lens_model_name, lens);
}

const char* lens_model_name(LensModel lens)
{
    return lens == LensModel::ThinLens ? "thin" : "optical";
}

void record_camera(OIIO::ImageSpec& spec, const Camera& c)
{
    spec.attribute("defocus:focalLength", float(c.focal_length_mm));
    spec.attribute("defocus:fNumber", float(c.fstop));
    spec.attribute("defocus:focusDistance", float(c.focus_distance));
    spec.attribute("defocus:filmbackWidth", float(c.sensor_width_mm));
    spec.attribute("defocus:maxBlur", float(c.max_blur_px));
    spec.attribute("defocus:lens", lens_model_name(c.lens));
}

bool check_camera(const Camera& c, std::string& error)
{
    auto fail = [&](std::string why) {
        error = std::move(why);
        return false;
    };
    auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
    if (!positive(c.focal_length_mm))
        return fail("focal length must be a positive number of mm");
    if (!positive(c.fstop))
        return fail("f-stop must be positive");
    if (!positive(c.focus_distance))
        return fail("focus distance must be positive");
    if (!positive(c.sensor_width_mm))
        return fail("sensor width must be a positive number of mm");
    if (!(c.max_blur_px >= 0.0) || !std::isfinite(c.max_blur_px))
        return fail("max blur must be a finite number of pixels >= 0");
    if (c.lens == LensModel::Optical
        && c.focus_distance <= c.focal_length_mm * 1e-3)
        return fail(OIIO::Strutil::fmt::format(
            "the optical lens cannot focus at {} (inside the focal length {} mm)",
            c.focus_distance, c.focal_length_mm));
    return true;
}

}  // namespace defocus
