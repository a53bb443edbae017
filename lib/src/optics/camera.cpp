#include <defocus/optics/camera.h>

#include <algorithm>
#include <cmath>

#include <OpenImageIO/strutil.h>

#include "util/parse_name.h"

namespace defocus {

namespace {

/// A display-window pixel as a point (its centre, pixel i's at i + 1/2);
/// none: the display window's centre.
Imath::V2d pixel_point(const std::optional<Imath::V2d>& pixel, const OIIO::ROI& display)
{
    if (!pixel)
        return { display.xbegin + 0.5 * display.width(), display.ybegin + 0.5 * display.height() };
    return *pixel + Imath::V2d(0.5, 0.5);
}

/// The focus point's share of the tilted plane's 1/z_f: 1/z_f along the
/// ray through normalised image position (u, v) (v down) is
/// (1 - tan(tilt_v) u + tan(tilt_h) v) / (this · focus distance), so this
/// is that numerator at the focus point, where 1/z_f is 1/focus distance.
struct TiltedPlane {
    double tan_h, tan_v;  ///< about the horizontal and the vertical axis
    double centre_x, centre_y;
    /// The focal length in rows, and in columns (rows over the pixel
    /// aspect: a wide pixel spans more of the field).
    double focal_px, focal_px_x;
    double focus_term;
};

TiltedPlane tilted_plane(const Camera& camera, const OIIO::ROI& display)
{
    constexpr double degree = 3.14159265358979323846 / 180.0;
    TiltedPlane p;
    p.tan_h = std::tan(camera.tilt_deg[0] * degree);
    p.tan_v = std::tan(camera.tilt_deg[1] * degree);
    p.centre_x = display.xbegin + 0.5 * display.width();
    p.centre_y = display.ybegin + 0.5 * display.height();
    p.focal_px = camera.focal_length_mm / camera.sensor_width_mm * display.width();
    p.focal_px_x = p.focal_px / camera.pixel_aspect;
    const Imath::V2d focus = pixel_point(camera.focus_pixel, display);
    p.focus_term = 1.0 - p.tan_v * (focus.x - p.centre_x) / p.focal_px_x
                   + p.tan_h * (focus.y - p.centre_y) / p.focal_px;
    return p;
}

}  // namespace

Imath::V2d optical_centre(const Camera& camera, const OIIO::ROI& display)
{
    return pixel_point(camera.axis_pixel, display);
}

CircleOfConfusion::CircleOfConfusion(const Camera& camera, const OIIO::ROI& display)
    : m_max_diameter(camera.max_blur_px)
    , m_axial_ca(camera.axial_ca)
{
    // f and s only appear as f/s and f (in scene units): focal length in
    // mm, converted to metres, the unit of depth.
    const double f = camera.focal_length_mm * 1e-3;
    const double f_over_s = camera.focal_length_mm / camera.sensor_width_mm;
    // In rows (the filmback spans the columns of the file, its pixels
    // square on the sensor, the squeeze in the lens), then as the diameter
    // of the disc of the footprint's area in the file's pixels: a round
    // bokeh on the desqueezed image is 1 / pixel_aspect as wide as tall in
    // them (see effective_aperture).
    m_scale = f * f_over_s / camera.fstop * display.width() / std::sqrt(camera.pixel_aspect);
    if (camera.lens == LensModel::Optical)
        m_scale *= camera.focus_distance / (camera.focus_distance - f);

    // The plane of focus through the focus point, with normal
    // (-tan_v, tan_h, 1) in camera space, meets the ray of (u, v) at
    // 1/z_f linear in u and v (see TiltedPlane). Untilted, m_inv_focus is
    // exactly 1/focus distance and the slopes are zero.
    const TiltedPlane p = tilted_plane(camera, display);
    const double k = 1.0 / (camera.focus_distance * p.focus_term);
    m_inv_focus
        = k * (1.0 + p.tan_v * p.centre_x / p.focal_px_x - p.tan_h * p.centre_y / p.focal_px);
    m_tilt_x = -k * p.tan_v / p.focal_px_x;
    m_tilt_y = k * p.tan_h / p.focal_px;

    if (camera.in_focus_range > 0.0) {
        const double near = camera.focus_distance - 0.5 * camera.in_focus_range;
        const double far  = camera.focus_distance + 0.5 * camera.in_focus_range;
        m_sharp_near = near > 0.0 ? 1.0 / near - 1.0 / camera.focus_distance : INFINITY;
        m_sharp_far  = 1.0 / camera.focus_distance - 1.0 / far;
    }

    // A diopter adds optical power, the same over its part of the frame:
    // the power that moves the focus from the focus distance to its own.
    const SplitDiopter& split = camera.split;
    if (split.distance > 0.0) {
        // In the desqueezed image's pixels, x times the pixel aspect, so
        // that the transition is as wide whichever way the line runs.
        const double aspect = camera.pixel_aspect;
        const double dx = (split.x1 - split.x0) * aspect, dy = split.y1 - split.y0;
        const double length = std::hypot(dx, dy);
        // On the right of the line's direction, as the image is seen (y down).
        m_split_nx = -dy * aspect / length;
        m_split_ny = dx / length;
        m_split_offset = m_split_nx * (split.x0 + 0.5) + m_split_ny * (split.y0 + 0.5);
        m_split_power = 1.0 / split.distance - 1.0 / camera.focus_distance;
    }
}

double CircleOfConfusion::depth_at(double c, int x, int y) const
{
    const double d     = c / m_scale + (c < 0.0 ? -m_sharp_near : c > 0.0 ? m_sharp_far : 0.0);
    const double inv_z = inverse_focus(x, y) - d;
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
    // OpenEXR's standard `focus` and `aperture` (OpenImageIO's FNumber)
    // describe the lens of the image: the one its blur was drawn with.
    spec.attribute("focus", float(c.focus_distance));
    spec.attribute("FNumber", float(c.fstop));
    if (c.tilt_deg[0] != 0.0 || c.tilt_deg[1] != 0.0) {
        const float tilt[2] = { float(c.tilt_deg[0]), float(c.tilt_deg[1]) };
        spec.attribute("defocus:focusTilt",
                       OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, OIIO::TypeDesc::VEC2), tilt);
    }
    if (c.in_focus_range != 0.0)
        spec.attribute("defocus:inFocusRange", float(c.in_focus_range));
    if (c.axial_ca != 0.0)
        spec.attribute("defocus:axialCA", float(c.axial_ca));
    if (c.lateral_ca != 0.0)
        spec.attribute("defocus:lateralCA", float(c.lateral_ca));
    if (c.cateye != 0.0)
        spec.attribute("defocus:catEye", float(c.cateye));
    if (c.split.distance > 0.0)
        spec.attribute("defocus:splitDiopter",
                       OIIO::Strutil::fmt::format("{},{},{},{}:{}", c.split.x0, c.split.y0,
                                                  c.split.x1, c.split.y1, c.split.distance));
}

bool check_camera(const Camera& c, const OIIO::ROI& display, std::string& error)
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
    // Seen nearly edge-on from the camera, a tilted plane's focus would
    // swing from near to infinity within the frame around the focus point.
    if (tilted_plane(c, display).focus_term < 0.1)
        return fail(OIIO::Strutil::fmt::format(
            "the focus tilt {},{} turns the plane of focus edge-on to the camera at the "
            "focus point", c.tilt_deg[0], c.tilt_deg[1]));
    if (!(c.in_focus_range >= 0.0) || !std::isfinite(c.in_focus_range))
        return fail("the in-focus range must be a finite depth >= 0");
    if (c.split.distance > 0.0 && c.split.x0 == c.split.x1 && c.split.y0 == c.split.y1)
        return fail("the split diopter's line needs two different points");
    return true;
}

}  // namespace defocus
