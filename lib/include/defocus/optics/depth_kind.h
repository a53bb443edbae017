// What a render's depth channel holds, and how it becomes the planar
// camera-space depth the rest of defocus works in.
#pragma once

#include <string>

#include <Imath/ImathVec.h>
#include <OpenImageIO/imageio.h>

#include <defocus/optics/camera.h>

namespace defocus {

enum class DepthKind {
    Z,         ///< planar camera-space depth
    /// 1/z: 0 is infinitely far. Nuke's renderers write depth so, and
    /// ZDefocus calls it "far = 0".
    Inverse,
    /// Distance from the camera's centre along the pixel's ray, as some
    /// renderers' depth AOVs give it.
    Distance,
    /// The signed CoC diameter in pixels, negative in front of the focus,
    /// as the coc AOV writes it: the blur itself, with no camera.
    Coc,
};

/// "z", "inverse", "distance" or "coc"; false for any other name.
bool parse_depth_kind(const std::string& name, DepthKind& kind);
const char* depth_kind_name(DepthKind kind);

/// The attribute a header declares its depth's kind with.
constexpr const char* depth_kind_attribute = "defocus:depthKind";

/// The kind `header` declares (depth_kind_attribute); false when it
/// declares none, or one defocus does not know.
bool header_depth_kind(const OIIO::ImageSpec& header, DepthKind& kind);

/// The camera of a CoC map: focused at depth 1, with the limiting CoC (that
/// of infinity) its max blur, so that the depth 1 / (1 - c / max blur) has
/// CoC diameter c, over `display`. Only the CoC it draws means anything.
Camera coc_map_camera(const CameraBody& body, const OIIO::ROI& display);

/// Planar depth from depth of one kind, pixel by pixel.
class PlanarDepth {
public:
    /// `camera` gives the rays (focal length, filmback, optical centre,
    /// pixel aspect) for distances, and is the CoC map's camera
    /// (coc_map_camera) for CoCs. Depths of kind Z and Distance were read
    /// multiplied by `depth_scale`, and so was an inverse depth, whose
    /// unit is 1 / the depth's unit.
    PlanarDepth(DepthKind kind, const Camera& camera, const OIIO::ROI& display,
                double depth_scale);

    DepthKind kind() const { return m_kind; }

    /// The planar depth of `value` seen at pixel (x, y): +inf for an inverse
    /// depth of 0 and for a CoC at or beyond that of infinity. NaN where
    /// the value means nothing (NaN; a negative inverse depth).
    double operator()(double value, int x, int y) const;

private:
    DepthKind m_kind;
    CircleOfConfusion m_coc;
    Imath::V2d m_centre;
    double m_focal_px, m_pixel_aspect, m_depth_scale;
};

}  // namespace defocus
