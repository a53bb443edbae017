#include <defocus/optics/depth_kind.h>

#include <algorithm>
#include <cmath>

#include "util/parse_name.h"

namespace defocus {

bool parse_depth_kind(const std::string& name, DepthKind& kind)
{
    return parse_name(name, { DepthKind::Z, DepthKind::Inverse, DepthKind::Distance, DepthKind::Coc },
                      depth_kind_name, kind);
}

const char* depth_kind_name(DepthKind kind)
{
    switch (kind) {
    case DepthKind::Z: return "z";
    case DepthKind::Inverse: return "inverse";
    case DepthKind::Distance: return "distance";
    case DepthKind::Coc: return "coc";
    }
    return "z";
}

bool header_depth_kind(const OIIO::ImageSpec& header, DepthKind& kind)
{
    const std::string declared = header.get_string_attribute(depth_kind_attribute);
    return !declared.empty() && parse_depth_kind(declared, kind);
}

Camera coc_map_camera(const CameraBody& body, const OIIO::ROI& display)
{
    Camera camera;
    static_cast<CameraBody&>(camera) = body;
    camera.lens           = LensModel::ThinLens;
    camera.in_focus_range = 0.0;
    camera.focus_distance = 1.0;
    // CircleOfConfusion's scale f^2 / (N s) W is the limiting CoC at focus
    // 1: the f-number that makes it the max blur (or 1 px, with none).
    const double limit = std::max(body.max_blur_px, 1.0);
    const double f = camera.focal_length_mm * 1e-3;
    camera.fstop = f * camera.focal_length_mm / camera.sensor_width_mm * display.width() / limit;
    return camera;
}

PlanarDepth::PlanarDepth(DepthKind kind, const Camera& camera, const OIIO::ROI& display,
                         double depth_scale)
    : m_kind(kind)
    , m_coc(camera, display)
    , m_centre(optical_centre(camera, display))
    , m_focal_px(camera.focal_length_mm / camera.sensor_width_mm * display.width())
    , m_pixel_aspect(camera.pixel_aspect)
    , m_depth_scale(depth_scale)
{
}

double PlanarDepth::operator()(double value, int x, int y) const
{
    if (std::isnan(value))
        return NAN;
    switch (m_kind) {
    case DepthKind::Z: return value;
    case DepthKind::Inverse:
        // Read as s / z_file: the depth in metres is s z_file = s^2 / value.
        if (value < 0.0)
            return NAN;
        return value == 0.0 ? INFINITY : m_depth_scale * m_depth_scale / value;
    case DepthKind::Distance: {
        // The ray through the pixel's centre, in units of the focal length:
        // the filmback's width spans the file's columns, each pixel_aspect
        // times as wide as it is tall in the scene.
        const double u = (x + 0.5 - m_centre.x) * m_pixel_aspect / m_focal_px;
        const double v = (y + 0.5 - m_centre.y) / m_focal_px;
        return value / std::sqrt(1.0 + u * u + v * v);
    }
    case DepthKind::Coc: return m_coc.depth_at(value, x, y);
    }
    return value;
}

}  // namespace defocus
