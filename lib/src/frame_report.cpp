#include <defocus/frame_report.h>

#include <algorithm>
#include <cmath>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>

#include <defocus/layers/layer_view.h>

namespace defocus {

using namespace OIIO;
using Strutil::fmt::format;

namespace {

/// Layer `index`'s colour in the layer view, as 8-bit hex ("#f2a13d").
std::string colour_name(int index)
{
    const Imath::V3f c = layer_colour(index);
    auto byte = [](float v) { return int(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); };
    return format("#{:02x}{:02x}{:02x}", byte(c.x), byte(c.y), byte(c.z));
}

/// The lines of -v on the depth, the camera, the pixel aspect and the
/// focal surface.
std::string camera_report(const FrameResult& frame, const Shot& shot)
{
    const Camera& c = frame.camera;
    std::string r;
    r += format("  depth: {} ({})\n", depth_kind_name(frame.depth.kind), frame.depth.origin);
    if (frame.depth.kind == DepthKind::Coc) {
        r += format("  camera: none, the depth is a CoC map; {} aperture, max blur {:.4g} px\n",
                    aperture_shape_name(shot.spread.aperture.shape), c.max_blur_px);
    } else {
        r += format("  camera: {:.4g} mm f/{:.3g} focus {:.4g}{} sensor {:.4g} mm, {} lens, {} "
                    "aperture, max blur {:.4g} px\n",
                    c.focal_length_mm, c.fstop, c.focus_distance,
                    c.in_focus_range > 0.0 ? format(" (sharp over {:.4g})", c.in_focus_range)
                                           : "",
                    c.sensor_width_mm, lens_model_name(c.lens),
                    aperture_shape_name(shot.spread.aperture.shape), c.max_blur_px);
        const CameraOrigins& o = frame.camera_origins;
        r += format("  camera values from: focal {}, f-number {}, focus {}, sensor {}\n",
                    o.focal_length, o.fstop, o.focus, o.sensor_width);
    }
    if (c.pixel_aspect != 1.0) {
        const ApertureShape shape = shot.spread.aperture.shape;
        const bool square = shape == ApertureShape::Tent || shape == ApertureShape::Smooth
                            || !shot.spread.psf_image.empty();
        r += format("  pixels {:.4g} times as wide as tall (the file's pixelAspectRatio): "
                    "blurred as the desqueezed image shows them{}\n",
                    c.pixel_aspect,
                    square ? format(", but the {} stays square in the file's pixels",
                                    shot.spread.psf_image.empty() ? "aperture" : "PSF image")
                           : "");
    }
    if (c.tilt_deg[0] != 0.0 || c.tilt_deg[1] != 0.0)
        r += format("  plane of focus tilted {:.4g},{:.4g} degrees\n", c.tilt_deg[0],
                    c.tilt_deg[1]);
    if (c.split.distance > 0.0)
        r += format("  split diopter beyond {:.6g},{:.6g} -> {:.6g},{:.6g}: focus {:.4g}\n",
                    c.split.x0, c.split.y0, c.split.x1, c.split.y1, c.split.distance);
    return r;
}

}  // namespace

std::string frame_report(const FrameResult& frame, const Shot& shot, const std::string& output)
{
    std::string r = camera_report(frame, shot);
    for (const std::string& note : frame.notes)
        r += "  " + note + "\n";
    r += "  " + frame.color.summary + "\n";
    if (!frame.bloom.empty())
        r += "  " + frame.bloom + "\n";
    if (!frame.slicing.empty())
        r += "  " + frame.slicing + "\n";
    if (!frame.rebuilt.empty())
        r += "  " + frame.rebuilt + "\n";
    for (const std::string* line : { &frame.edges, &frame.holdout, &frame.data })
        if (!line->empty())
            r += "  " + *line + "\n";
    if (!frame.layers.empty())
        r += "  layers, back to front:\n";
    int64_t slow = 0, covered = 0;
    for (size_t i = 0; i < frame.layers.size(); ++i) {
        const LayerReport& l = frame.layers[i];
        r += format("    {:<12} {:>9} px  depth {:.4g}..{:.4g}  CoC {:.3g}..{:.3g} px{}\n",
                    l.name, l.pixels, l.depth_min, l.depth_max, l.coc_min, l.coc_max,
                    shot.output == OutputKind::Layers ? "  drawn " + colour_name(int(i)) : "");
        slow += l.psf_pixels;
        covered += l.pixels;
    }
    if (!shot.spread.psf_image.empty())
        r += format("  hybrid: {} of {} pixels ({:.2f}%) spread with the PSF image\n", slow,
                    covered, covered ? 100.0 * slow / covered : 0.0);
    const SubApertureReport& cells = frame.cells;
    if (cells.tiles > 0)
        r += format("  sub-aperture: {} of {} tiles ({:.1f}%) composited per part of the lens, "
                    "in up to {} cells; {} of them over blocks of pixels\n",
                    cells.tiles_with_cells, cells.tiles,
                    100.0 * cells.tiles_with_cells / cells.tiles, cells.most_cells,
                    cells.tiles_over_blocks);
    r += format("  pixels fixed: {} with NaN/inf colour dropped, {} with colour beyond 1e30 "
                "clamped, {} with alpha above 1 clamped to 1, {} with bad depth taken as "
                "infinitely far, {} transparent with colour cleared, {} edge pixels without "
                "depth given their neighbours'\n",
                frame.fixed.nonfinite_color, frame.fixed.huge_color,
                frame.fixed.alpha_above_one, frame.fixed.bad_depth,
                frame.fixed.transparent_light, frame.fixed.edge_depth);
    for (const auto& [stage, seconds] : frame.timings)
        r += format("  {:<10} {:7.3f} s\n", stage, seconds);
    if (!frame.overlap.empty())
        r += "  side by side: " + frame.overlap + "\n";
    const ImageSpec& spec = frame.image.spec();
    r += format("  wrote {} ({}x{} data window, {})\n", output, spec.width, spec.height,
                frame.pixel_type);
    return r;
}

bool preview_image(const FrameResult& frame, const std::string& display, const std::string& view,
                   bool keep_alpha, ImageBuf& preview, std::string& error)
{
    if (!frame.color.config) {
        error = frame.color.summary;
        return false;
    }
    const ColorManagement& c = *frame.color.config;
    const std::string shown_on = display.empty() ? c.default_display() : display;
    const std::string seen_as = view.empty() ? c.default_view(shown_on) : view;
    // A deep result is shown as it flattens.
    const ImageBuf flat = frame.image.deep() ? ImageBufAlgo::flatten(frame.image) : ImageBuf();
    const ImageBuf& image = frame.image.deep() ? flat : frame.image;
    const ImageSpec& spec = image.spec();
    ImageBuf framed;
    ImageBufAlgo::crop(framed, image,
                       ROI(spec.full_x, spec.full_x + spec.full_width, spec.full_y,
                           spec.full_y + spec.full_height, 0, 1, 0, spec.nchannels));
    // Premultiplied colour over black is the colour itself, without alpha.
    if (!keep_alpha && spec.nchannels > 3)
        framed = ImageBufAlgo::channels(framed, 3, { 0, 1, 2 });
    else if (frame.image.deep())  // without its depths
        framed = ImageBufAlgo::channels(framed, 4, { 0, 1, 2, 3 });
    return c.display(preview, framed, frame.color.output, shown_on, seen_as, error);
}

}  // namespace defocus
