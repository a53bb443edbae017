// The camera: which lens draws which circle of confusion.
#pragma once

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include <Imath/ImathVec.h>
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
    /// Axial (longitudinal) chromatic aberration: the CoC of red and blue
    /// is green's scaled by 1 + axial_ca in front of the focus and by
    /// 1 - axial_ca behind it (see CocChannel); 0 = none.
    double axial_ca        = 0.0;
    /// Lateral chromatic aberration: red is magnified by 1 + lateral_ca and
    /// blue by 1 - lateral_ca about the optical centre, relative to green.
    double lateral_ca      = 0.0;
    /// Optical vignetting, the cat's eye bokeh (see CatEye): 0 = none.
    double cateye          = 0.0;
    /// The depth range around the focus distance that stays sharp, as
    /// Nuke ZDefocus's "depth of field": depths within half of it of the
    /// focus have no blur, and beyond it the blur grows from its ends.
    double in_focus_range  = 0.0;
};

/// Which colour's circle of confusion. Under axial chromatic aberration
/// (CameraBody::axial_ca = a) red and blue focus alike and green apart: of
/// a point whose green CoC diameter is c (signed, negative in front of the
/// focus), red and blue have c - a |c|, that is c (1 + a) in front and
/// c (1 - a) behind. With a > 0, bokeh in front of the focus has purple
/// rims and behind it green ones, as a fast lens shows, and nothing in
/// focus is fringed.
enum class CocChannel { Green, RedBlue };

/// A split-field diopter: a half lens over part of the frame. Beyond the
/// line from (x0, y0) to (x1, y1) (display-window pixels), on the right
/// walking from the first point to the second as the image is seen, the
/// focus is at `distance`; across the line it changes over a few pixels.
struct SplitDiopter {
    double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    double distance = 0;  ///< 0: no diopter
};

/// Camera settings at one frame, in the units a cinematographer uses.
/// Depths and the focus distance share the scene's unit (metres for most
/// renderers).
struct Camera : CameraBody {
    double focal_length_mm = 50.0;
    double fstop           = 2.8;
    double focus_distance  = 1.0;
    /// The pixel where the focus distance is measured, in display-window
    /// pixels; none: the display window's centre (the optical axis).
    std::optional<Imath::V2d> focus_pixel;
    /// The plane of focus tilted (Scheimpflug) about the horizontal and
    /// the vertical axis through the focus point, in degrees: positive
    /// turns its top, and its right side, away from the camera.
    double tilt_deg[2] = { 0.0, 0.0 };
    SplitDiopter split;
    /// The pixel where the lens's axis meets the image, in display-window
    /// pixels, for lateral chromatic aberration; none: the display
    /// window's centre.
    std::optional<Imath::V2d> axis_pixel;
    /// The width of a pixel over its height in the scene (the file's
    /// pixelAspectRatio): 2 for a plate squeezed 2x by an anamorphic lens.
    /// The filmback spans the file's columns; blur is drawn as it would be
    /// seen on the desqueezed image.
    double pixel_aspect = 1.0;
};

/// The circle of confusion of one camera over a display window, precomputed
/// for per-pixel use. The lens focuses on a surface: a plane parallel to
/// the sensor, tilted, or split by a diopter, so the blur of a depth
/// depends on where in the frame it is seen.
class CircleOfConfusion {
public:
    CircleOfConfusion(const Camera& camera, const OIIO::ROI& display);

    /// Signed CoC diameter in pixels of a point at planar camera-space depth
    /// `z` (+inf is allowed and means infinitely far) seen at pixel (x, y).
    /// Negative in front of the focus surface; the magnitude never exceeds
    /// the camera's max blur.
    double diameter(double z, int x, int y) const
    {
        return std::clamp(unclamped(z, x, y), -m_max_diameter, m_max_diameter);
    }

    /// The same for one colour (see CocChannel).
    double diameter(double z, int x, int y, CocChannel channel) const
    {
        double c = unclamped(z, x, y);
        if (channel == CocChannel::RedBlue)
            c -= m_axial_ca * std::abs(c);
        return std::clamp(c, -m_max_diameter, m_max_diameter);
    }

    /// The unsigned radius |c|/2 that spreading uses.
    double radius(double z, int x, int y) const { return 0.5 * std::abs(diameter(z, x, y)); }

    /// True when red and blue have a CoC of their own (axial chromatic
    /// aberration).
    bool per_channel() const { return m_axial_ca != 0.0; }

    /// True when the CoC of a depth depends on where in the frame it is
    /// seen (a tilted plane, a diopter). Otherwise it depends on the depth
    /// alone, and never decreases with it, so a range of depths has the
    /// range of CoCs of its ends.
    bool varies_over_frame() const
    {
        return m_tilt_x != 0.0 || m_tilt_y != 0.0 || m_split_power != 0.0;
    }

    /// The depth at pixel (x, y) whose unclamped signed CoC diameter is `c`
    /// (+inf when c is the CoC of infinity, or beyond it).
    double depth_at(double c, int x, int y) const;

    /// 1 / the distance the lens focuses at along the ray of pixel (x, y).
    double inverse_focus(int x, int y) const
    {
        const double px = x + 0.5, py = y + 0.5;
        double inverse = m_inv_focus + m_tilt_x * px + m_tilt_y * py;
        if (m_split_power != 0.0) {
            const double beyond = m_split_nx * px + m_split_ny * py - m_split_offset;
            inverse += m_split_power * std::clamp(beyond / split_transition_px + 0.5, 0.0, 1.0);
        }
        return inverse;
    }

    /// Pixels over which a split diopter's focus changes across its line.
    static constexpr double split_transition_px = 4.0;

private:
    double unclamped(double z, int x, int y) const
    {
        const double inv_z = 1.0 / z;  // 0 at infinity
        // Thin lens (the paper's eq. 1 with the image plane fixed):
        //   c = f^2 / (N s) * W * (1/z_f - 1/z).
        // Potmesil & Chakravarty: f^2 |z - z_f| / (N z (z_f - f)) * W/s,
        // the same expression times z_f / (z_f - f), folded into m_scale.
        // An in-focus range takes its span of 1/z_f - 1/z out, so the blur
        // starts at its ends; with none, this is the plain difference.
        const double d = inverse_focus(x, y) - inv_z;
        return m_scale * (d - std::min(std::max(d, -m_sharp_near), m_sharp_far));
    }

    double m_scale;  ///< pixels per unit of |1/z_f - 1/z| (thin lens)
    /// 1/z_f is linear over the frame for a plane, tilted or not:
    /// m_inv_focus + m_tilt_x x + m_tilt_y y.
    double m_inv_focus, m_tilt_x = 0.0, m_tilt_y = 0.0;
    /// A diopter adds m_split_power to 1/z_f beyond the line
    /// n . (x, y) = m_split_offset (n a unit normal, pointing beyond).
    double m_split_power = 0.0, m_split_nx = 0.0, m_split_ny = 0.0, m_split_offset = 0.0;
    /// The in-focus range's span of 1/z in front of the focus (to its
    /// near end; infinite when that end is at or behind the camera) and
    /// behind it (to its far end).
    double m_sharp_near = 0.0, m_sharp_far = 0.0;
    double m_max_diameter;
    double m_axial_ca;
};

/// "thin" or "optical"; false when the name is neither.
bool parse_lens_model(const std::string& name, LensModel& lens);
const char* lens_model_name(LensModel lens);

/// Records the camera as attributes defocus:focalLength, defocus:fNumber,
/// defocus:focusDistance, defocus:filmbackWidth, defocus:maxBlur and
/// defocus:lens.
void record_camera(OIIO::ImageSpec& spec, const Camera& camera);

/// Where the lens's axis meets the image (Camera::axis_pixel, else the
/// display window's centre), with pixel i's centre at i + 1/2.
Imath::V2d optical_centre(const Camera& camera, const OIIO::ROI& display);

/// True when the camera's settings are valid over the display window; else
/// false with `error` the first problem.
bool check_camera(const Camera& camera, const OIIO::ROI& display, std::string& error);

}  // namespace defocus
