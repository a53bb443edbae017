// Helpers shared by the tests: synthetic layers, the garden metric, paths.
#pragma once

#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <defocus/layers/layered_scene.h>
#include <defocus/render_frame.h>
#include <defocus/scene.h>
#include <defocus/optics/camera.h>
#include <defocus/spread/footprint.h>

namespace defocus_test {

using OIIO::ImageBuf;
using OIIO::ROI;

/// The first subimage of `file` as float, as it is on disk now (the tools
/// rewrite files under one name, which OpenImageIO's shared cache would
/// not see; see defocus::read_image_file). Empty when unreadable.
ImageBuf read_image(const std::string& file);

/// The header of a subimage of `file` as it is on disk now (as
/// read_image), and how many subimages it has. Empty spec / 0 when
/// unreadable.
OIIO::ImageSpec read_spec(const std::string& file, int subimage = 0);
int count_subimages(const std::string& file);

/// `scene` layered for `camera`, as the layering stage gives it (scenes
/// of layers only: described and ordered back to front).
defocus::LayeredScene layered_scene(defocus::Scene scene, const defocus::Camera& camera);

/// A float image of `nchannels` over `roi`, all zero.
ImageBuf zero_image(const ROI& roi, int nchannels);

/// The synthetic scenes' camera: over a 120-pixel-wide frame its CoC is
/// k·(1/focus - 1/z) with k = f²/(N s)·W = 0.1·(100/36)·120 = 33.3 px.
defocus::Camera synthetic_camera(double focus);

/// A hexagonal aperture, turned by 10 degrees.
defocus::Aperture hexagon();

/// An impulse: one RGBA pixel of 1 at the origin.
ImageBuf impulse();

/// A one-channel radius image of constant r over roi.
ImageBuf constant_radius(const ROI& roi, float r);

/// How continuously a footprint grows: the largest L1 change of channel 0
/// between spread_at(r) for consecutive r = r0, r0 + step, ... (count
/// steps), over the union of their windows.
double largest_footprint_step(const std::function<ImageBuf(float)>& spread_at, float r0,
                              float step, int count);

/// Deterministic uniform random values in [0, 1).
class Random {
public:
    explicit Random(unsigned seed) : m_state(seed * 2654435761u + 1u) {}
    double uniform();
private:
    unsigned long long m_state;
};

/// A layer of random premultiplied RGBA in [0.01, 10) over roi, and random
/// radii in [rmin, rmax].
void random_layer(const ROI& roi, double rmin, double rmax, unsigned seed, ImageBuf& color,
                  ImageBuf& radius);

/// The direct reference of a spread: over an image like `like`, every
/// pixel (x, y) of `color` adds footprint(x, y, its radius) times its value.
ImageBuf direct_sum(const ImageBuf& color, const ImageBuf& radius, const ImageBuf& like,
                    const std::function<defocus::Footprint(int, int, double)>& footprint);

/// A bright point (1000) at `at` on a dim random field (under 0.01) over
/// roi, every pixel of CoC radius 40: a highlight whose bokeh shows.
void highlight_on_dim_field(const ROI& roi, const Imath::V2i& at, ImageBuf& color,
                            ImageBuf& radius);

/// The largest difference between two flat images over their union.
float largest_difference(const ImageBuf& a, const ImageBuf& b);

/// Sum of channel `c` over the whole data window, in double.
double channel_sum(const ImageBuf& image, int c);

/// Largest |a - b| / (|b| * rel + abs) over the union of both windows,
/// missing pixels being zero: <= 1 means a matches b within the bar.
double worst_relative_error(const ImageBuf& a, const ImageBuf& b, double rel,
                            double abs);

/// The garden README's metric: PSNR in dB of R, G, B over the display
/// window of `truth`, after sRGB encoding and clamping to [0, 1]. Pixel
/// (x, y) of the truth is compared with (x + dx, y + dy) of the result.
double garden_psnr(const ImageBuf& result, const ImageBuf& truth, int dx = 0, int dy = 0);

/// Runs a shell command, returns its exit status; stdout+stderr into `output`.
int run(const std::string& command, std::string& output);

/// The defocus command under test.
extern const std::string defocus_bin;

/// This machine's name as the tools write it into temporary files' names.
std::string this_host();

/// Settings by name and value, as set_shot_setting() takes them:
/// { "focal", "50" }.
using Settings = std::vector<std::pair<std::string, std::string>>;

/// The spec of a flat render: float R, G, B, A and Z.
OIIO::ImageSpec rgbaz_spec(int width, int height);

/// A 20x20 RGBA+Z render in `dir`: grey at 2 m on the left half, blue at
/// 6 m on the right; its path.
std::string two_depth_scene(const std::string& dir);

/// A shot of `inputs` with `settings`, which must be valid.
defocus::Shot shot_with(const std::vector<std::string>& inputs, const Settings& settings);

/// Frame `frame` of `shot` rendered through the library (check_shot,
/// read_shot_assets, render_frame); false with the first error on the way.
bool render_shot(const defocus::Shot& shot, defocus::FrameResult& result, std::string& error,
                 int frame = 1);

/// Frame `frame` of `inputs` rendered through the library (render_frame),
/// with `settings`; false with the first error on the way.
bool render_with(const std::vector<std::string>& inputs, const Settings& settings,
                 defocus::FrameResult& result, std::string& error, int frame = 1);
inline bool render_with(const std::string& input, const Settings& settings,
                        defocus::FrameResult& result, std::string& error, int frame = 1)
{
    return render_with(std::vector<std::string> { input }, settings, result, error, frame);
}

/// render_with()'s image, which must render.
ImageBuf rendered(const std::string& input, const Settings& settings, int frame = 1);

/// True where no pixel of `image` is NaN or infinite.
bool no_nan(const ImageBuf& image);

/// Writes a `width` x `height` image of the given channels, every pixel
/// `pixel`, as `type`.
void write_uniform_image(const std::string& path, const std::vector<std::string>& channels,
                         const std::vector<float>& pixel, int width = 16, int height = 16,
                         OIIO::TypeDesc type = OIIO::TypeFloat);

/// The error of a .dof text that must be refused (checked: one line, naming
/// its source "shot.dof"), its paths resolved against `directory`.
std::string dof_error(const std::string& text, const std::string& directory = "");

/// The example scene (make_example_scene) at 320x180, made once per test
/// program.
std::string example_scene();

/// True when the text is one line (ending in a newline) mentioning `what`.
bool one_line_naming(const std::string& text, const std::string& what);

/// True where a library error is one line (no newline at all) containing
/// `what`, its settings worded as the command line writes them.
bool one_line_error(const std::string& error, const std::string& what);

/// A library message with its settings worded as the command line writes
/// them ("--focus-at 10,20").
std::string command_line_words(const std::string& message);

/// Writes a scanline OpenEXR (half R,G,B,A,Z, zip) whose header declares a
/// `width` x `height` data window, with its chunk table but one tiny
/// chunk: what a damaged or hostile header looks like to a reader that
/// trusts it.
void write_exr_header_only(const std::string& path, int width, int height);

/// The shared data folder (../shared/data beside the source tree, or
/// $DEFOCUS_SHARED_DATA), or "" when it is absent.
std::string shared_data();

/// A fresh empty scratch directory for one test.
std::string scratch_dir(const std::string& name);

}  // namespace defocus_test
