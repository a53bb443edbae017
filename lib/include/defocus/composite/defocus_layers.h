// Depth of field of a layered scene: spread each layer with its own
// per-pixel CoC, composite back to front with "over" on the spread alpha.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <defocus/layers/layered_scene.h>
#include <defocus/scene.h>
#include <defocus/optics/camera.h>
#include <defocus/shot/options.h>
#include <defocus/spread/aperture_images.h>

namespace defocus {

/// The CoC radius |c|/2 in pixels of every pixel of `depth` (one float
/// channel) over `roi`, for green (the camera's CoC) or for red and blue.
bool coc_radius(OIIO::ImageBuf& dst, const OIIO::ImageBuf& depth,
                const CircleOfConfusion& coc, OIIO::ROI roi = {},
                int nthreads = 0, CocChannel channel = CocChannel::Green);

/// The spec of a defocused result over `window`: R, G, B, A of type
/// `format`, in the display window of `scene` (a scene's spec). Its
/// metadata is left to the caller.
OIIO::ImageSpec result_spec(const OIIO::ImageSpec& scene, const OIIO::ROI& window,
                            OIIO::TypeDesc format);

/// How much of a frame was composited per part of the aperture (see
/// SpreadOptions::aperture_cells): its tiles, those that took cells, the
/// most cells one took, and of those with cells, how many were found over
/// blocks of 2 x 2 or 4 x 4 pixels (where every footprint through a cell
/// is several blocks wide).
struct SubApertureReport {
    int64_t tiles = 0;
    int64_t tiles_with_cells = 0;
    int most_cells = 0;
    int64_t tiles_over_blocks = 0;
};

/// What defocus_layers() reports beside the image.
struct SpreadStats {
    double spread = 0.0;  ///< seconds: CoC radii, spreading and compositing, all layers
    SubApertureReport cells;
};

/// Spreads each layer of a sanitized (see sanitize()), layered scene as
/// `spread` says, through `camera`, with the images the options name read
/// beforehand (read_aperture_images), and composites the layers back to
/// front: the defocused, flattened premultiplied RGBA over `window`, in the
/// scene's display window, without metadata. `report`, when given, lists
/// the layers' reports in that order, with the pixels the hybrid method
/// spread with its PSF image. When `dst` already holds float RGBA pixels
/// of that window (the last frame of a sequence), they are overwritten in
/// place rather than allocated afresh.
bool defocus_layers(OIIO::ImageBuf& dst, const LayeredScene& scene, const Camera& camera,
                    const SpreadOptions& spread = {}, const ApertureImages& images = {},
                    OutputWindow window = OutputWindow::Input,
                    std::vector<LayerReport>* report = nullptr,
                    SpreadStats* stats = nullptr, int nthreads = 0);

/// defocus_layers() for a caller done with the layers' pixels: each
/// layer's depth is freed once its CoC radii are made, and its colour (and
/// rebuilt mask and data channels) once it is composited; names, reports,
/// spec and holdout stay. The back-most layer, often the largest, is then
/// gone before the nearer ones are set up: a 4K frame's peak memory falls
/// by about a fifth. On failure the layers may be part freed.
bool defocus_layers_freeing(OIIO::ImageBuf& dst, LayeredScene& scene, const Camera& camera,
                            const SpreadOptions& spread = {}, const ApertureImages& images = {},
                            OutputWindow window = OutputWindow::Input,
                            std::vector<LayerReport>* report = nullptr,
                            SpreadStats* stats = nullptr, int nthreads = 0);

/// Receives one layer's spread, composited alone onto black: its index in
/// the scene, and float RGBA over the part of the result's `window` it
/// lights (it is black in the rest). False stops the spreading, with the
/// receiver's own error.
using LayerSink = std::function<bool(size_t layer, const OIIO::ImageBuf& spread,
                                     const OIIO::ROI& window)>;

/// defocus_layers() with each layer composited onto black alone and handed
/// to `sink`, back to front, rather than over the others: the window is the
/// one defocus_layers() gives, and compositing the layers
/// with "over" in that order gives its image, except for the scene's
/// holdout, which is not applied, and chromatic aberration, whose colours
/// each have their own alpha. Layers without pixels are left out.
/// False with `error` where spreading fails (the sink's own errors are its
/// own to keep).
bool spread_layers_apart(const LayeredScene& scene, const Camera& camera,
                         const SpreadOptions& spread, const ApertureImages& images,
                         OutputWindow window, const LayerSink& sink, std::string& error,
                         std::vector<LayerReport>* report = nullptr,
                         SpreadStats* stats = nullptr, int nthreads = 0);

/// spread_layers_apart() for a caller done with the layers' pixels, freed
/// as defocus_layers_freeing() frees them: each before the next layer is
/// spread. On failure the layers may be part freed.
bool spread_layers_apart_freeing(LayeredScene& scene, const Camera& camera,
                                 const SpreadOptions& spread, const ApertureImages& images,
                                 OutputWindow window, const LayerSink& sink,
                                 std::string& error,
                                 std::vector<LayerReport>* report = nullptr,
                                 SpreadStats* stats = nullptr, int nthreads = 0);

/// A layer's spread reaches a pixel where its coverage there is above
/// this: below it, float noise of the spread is too large a part of a
/// quantity spread times alpha (the CoC AOV, data channels).
constexpr float reach_coverage = 1e-3f;

/// What decides how far each layer's light reaches, not its colour: a
/// camera and spread less chromatic aberration and the PSF image. Quantities
/// spread as colour (the CoC AOV, data channels) are spread with it.
struct ReachOnly {
    Camera camera;
    SpreadOptions spread;
    ApertureImages images;
};

ReachOnly reach_only(const Camera& camera, const SpreadOptions& spread,
                     const ApertureImages& images);

/// The largest window defocus_layers() gives with OutputWindow::Grown for
/// layers within the data window of `scene` (a scene's spec), extended
/// past it by extend_edges(), at the largest blur `camera` allows (its max
/// blur): what a frame's grown window is known to fit in from the headers
/// alone. Found by spreading a uniform probe at that blur in the data
/// window's corners, so that it follows the filters, edges, blocks and all.
/// False with `error` when the probe cannot be spread (a mask aperture
/// without its image, out of memory).
bool largest_grown_window(OIIO::ROI& window, const OIIO::ImageSpec& scene, const Camera& camera,
                          const SpreadOptions& spread, const ApertureImages& images,
                          std::string& error, int nthreads = 0);

}  // namespace defocus
