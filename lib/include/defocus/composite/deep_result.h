// A defocused scene as a deep image, to merge with other elements later as
// deep compositing does: each layer's spread is one sample per pixel at the
// layer's depths.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <defocus/composite/defocus_layers.h>
#include <defocus/layers/layered_scene.h>
#include <defocus/optics/camera.h>
#include <defocus/scene.h>
#include <defocus/shot/options.h>
#include <defocus/spread/aperture_images.h>

namespace defocus {

/// One layer of a deep result: the pixels its spread lights (indices within
/// the result's window, row by row) with their premultiplied RGBA, as the
/// layer composites alone onto black, and the depths its samples span.
struct DeepLayer {
    std::vector<uint32_t> pixels;
    std::vector<float> rgba;  ///< 4 a pixel
    float z = 0.0f, zback = 0.0f;
};

/// A defocused scene as deep samples, one in each pixel for each layer
/// that reaches it.
struct DeepResult {
    OIIO::ROI window;  ///< the result's data window
    std::vector<DeepLayer> layers;  ///< front to back
};

/// The defocused `scene` as deep samples over the window defocus_layers()
/// gives. Every layer whose spread reaches a pixel is a sample there:
/// premultiplied RGBA as the layer composites alone onto black, spanning
/// the layer's depths (its report's depth_min to depth_max), each range cut
/// where it would reach into the one in front, so that the samples are
/// sorted front to back and do not overlap. Flattened front to back
/// ("over"), they give defocus_layers()'s image. The camera must have no
/// chromatic aberration (each colour has its own alpha there), and the
/// scene's holdout is not applied (merge the result with it instead).
/// False with `error` where spreading fails.
bool defocus_deep(DeepResult& dst, const LayeredScene& scene, const Camera& camera,
                  const SpreadOptions& spread, const ApertureImages& images,
                  OutputWindow window, std::string& error,
                  std::vector<LayerReport>* report = nullptr, SpreadStats* stats = nullptr,
                  int nthreads = 0);

/// defocus_deep() for a caller done with the layers' pixels, freed as
/// defocus_layers_freeing() frees them: each layer's colour is gone before
/// the next one's samples are made. A 4K frame's peak memory falls by a
/// fifth. On failure the layers may be part freed.
bool defocus_deep_freeing(DeepResult& dst, LayeredScene& scene, const Camera& camera,
                          const SpreadOptions& spread, const ApertureImages& images,
                          OutputWindow window, std::string& error,
                          std::vector<LayerReport>* report = nullptr,
                          SpreadStats* stats = nullptr, int nthreads = 0);

/// The spec of a deep result over `window`: R, G, B, A of `color_type` and
/// Z, ZBack of float, in the display window of `scene` (a scene's spec),
/// with its metadata.
OIIO::ImageSpec deep_result_spec(const OIIO::ImageSpec& scene, const OIIO::ROI& window,
                                 OIIO::TypeDesc color_type);

/// What deep_buffer() allocates per sample (colour and alpha of
/// `color_type`, two float depths) and per pixel of the window (OpenImageIO
/// keeps a count, a capacity and an offset).
inline double deep_sample_bytes(OIIO::TypeDesc color_type)
{
    return 4.0 * double(color_type.size()) + 8.0;
}
constexpr double deep_pixel_bytes = 12.0;

/// `result` as OpenImageIO's deep ImageBuf over its window, to write or to
/// hand to a host, with the spec deep_result_spec() gives. Each layer is
/// freed once its samples are placed.
OIIO::ImageBuf deep_buffer(DeepResult&& result, const OIIO::ImageSpec& scene,
                           OIIO::TypeDesc color_type, int nthreads = 0);

}  // namespace defocus
