// A scene cut into layers: what layering gives the stages after it (the
// edges, spreading and compositing, the focus map), which need no check
// that it ran.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Imath/ImathVec.h>
#include <OpenImageIO/imageio.h>

#include <defocus/color/color.h>
#include <defocus/scene.h>
#include <defocus/optics/camera.h>

namespace defocus {

/// What one layer holds, for -v and layerize --info.
struct LayerReport {
    std::string name;
    int64_t pixels = 0;  ///< pixels with alpha > 0
    double depth_min = 0, depth_max = 0;
    double coc_min = 0, coc_max = 0;  ///< signed CoC diameters, pixels
    double mean_inverse_depth = 0;    ///< alpha-weighted; orders the layers
    int64_t psf_pixels = 0;           ///< spread with the PSF image (hybrid)
};

/// Pixel count and depth and CoC ranges of a layer's covered pixels.
LayerReport describe_layer(const Layer& layer, const CircleOfConfusion& coc,
                           int nthreads = 0);

/// A scene's layers, back to front, each with its report.
struct LayeredScene {
    std::string source;  ///< the file(s) it came from, for messages
    /// Display window, pixel type and metadata of the input (Scene::spec).
    OIIO::ImageSpec spec;
    std::vector<Layer> layers;         ///< back to front
    std::vector<LayerReport> reports;  ///< one per layer, in the same order
    /// The weights of R, G and B in luminance, in the layers' colour space
    /// (the working space of the colour plan), by which highlights are
    /// found.
    Imath::V3d luma = luma_weights(nullptr);
    /// What cuts the layers where it stands in front of them, front to back
    /// in each pixel (see composite/holdout.h); null or no samples:
    /// nothing. Shared, not copied, by the scenes made from this one (the
    /// rebuilt part of the confidence AOV).
    std::shared_ptr<const DeepImage> holdout;
};

/// The layers of `scene` that carry light (pixels in their reports), by
/// index, back to front.
std::vector<size_t> lit_layers(const LayeredScene& scene);

/// The spec of a false-colour picture of `scene` (the focus map, the
/// layer view): float RGBA over its display window.
OIIO::ImageSpec display_picture_spec(const LayeredScene& scene);

/// Crops a layer (colour, depth and rebuilt) to the pixels that carry
/// light, as layering hands layers on.
void crop_to_content(Layer& layer, int nthreads = 0);

/// Describes every layer of `scene` and orders them back to front.
void order_layers(LayeredScene& scene, const CircleOfConfusion& coc, int nthreads = 0);

/// Orders the layers back to front by their reports' alpha-weighted mean
/// inverse depth, keeping the order of those alike.
void sort_back_to_front(LayeredScene& scene);

}  // namespace defocus
