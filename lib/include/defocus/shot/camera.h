// The camera: which lens draws which circle of confusion.
#pragma once

#include <cmath>
#include <string>

#include <OpenImageIO/imageio.h>

namespace defocus {

/// How depth maps to blur.
enum class LensModel {
    /// Render cameras (pbrt, Cycles, Arnold): the field of view is fixed by
    /// the focal length, so the lens does not breathe.
    ThinLens,
    /// Potmesil & Chakravarty's optical thin lens, whose image distance
    /// grows as it focuses closer.
    Optical,
};

/// What a camera keeps for a whole shot: its filmback, its lens model and
/// the largest blur it draws.
struct CameraBody {
    double sensor_width_mm = 36.0;   ///< horizontal filmback
    LensModel lens         = LensModel::ThinLens;
    double max_blur_px     = 512.0;  ///< clamp on the CoC diameter
};

/// Camera settings at one frame, in the units a cinematographer uses.
/// Depths and the focus distance share the scene's unit (metres for most
/// renderers).
struct Camera : CameraBody {
    double focal_length_mm = 50.0;
    double fstop           = 2.8;
    double focus_distance  = 1.0;
};

/// The circle of confusion of one camera over an image `display_width`
/// pixels wide, precomputed for per-pixel use.
class CircleOfConfusion {
public:
    CircleOfConfusion(const Camera& camera, int display_width);

    /// Signed CoC diameter in pixels of a point at planar camera-space depth
    /// `z` (+inf is allowed and means infinitely far). Negative in front of
    /// the focus plane; the magnitude never exceeds the camera's max blur.
    double diameter(double z) const;

    /// The unsigned radius |c|/2 that spreading uses.
    double radius(double z) const { return 0.5 * std::abs(diameter(z)); }

    /// The depth whose unclamped signed CoC diameter is `c` (+inf when c
    /// is the CoC of infinity, or beyond it).
    double depth_at(double c) const;

private:
    LensModel m_lens;
    double m_scale;  ///< pixels per unit of |1/z_f - 1/z| (thin lens)
    double m_focus;
    double m_inv_focus;
    double m_max_diameter;
};

/// "thin" or "optical"; false when the name is neither.
bool parse_lens_model(const std::string& name, LensModel& lens);
const char* lens_model_name(LensModel lens);

/// Records the camera as attributes defocus:focalLength, defocus:fNumber,
/// defocus:focusDistance, defocus:filmbackWidth, defocus:maxBlur and
/// defocus:lens.
void record_camera(OIIO::ImageSpec& spec, const Camera& camera);

/// True when the camera's settings are valid; else false with `error` the
/// first problem.
bool check_camera(const Camera& camera, std::string& error);

}  // namespace defocus
