// A defocused scene as a deep image, to merge with other elements later as
// deep compositing does: each layer's spread is one sample per pixel at the
// layer's depths.
#pragma once

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

/// The defocused `scene` as a deep image over the window defocus_layers()
/// gives. In each pixel, every layer whose spread reaches it is one sample:
/// premultiplied RGBA as the layer composites alone onto black, spanning
/// the layer's depths (its report's depth_min to depth_max). Samples run
/// front to back, each depth range cut where it would reach into the one
/// in front, so that they are sorted and do not overlap. Flattened front
/// to back ("over"), they give defocus_layers()'s image. The camera must
/// have no chromatic aberration (each colour has its own alpha there), and
/// the scene's holdout is not applied (merge the result with it instead).
/// False with `error` where spreading fails.
bool defocus_deep(DeepImage& dst, const LayeredScene& scene, const Camera& camera,
                  const SpreadOptions& spread, const ApertureImages& images,
                  OutputWindow window, std::string& error,
                  std::vector<LayerReport>* report = nullptr, SpreadTimings* timings = nullptr,
                  int nthreads = 0);

/// The spec of a deep result over `window`: R, G, B, A of `color_type` and
/// Z, ZBack of float, in the display window of `scene` (a scene's spec),
/// with its metadata.
OIIO::ImageSpec deep_result_spec(const OIIO::ImageSpec& scene, const OIIO::ROI& window,
                                 OIIO::TypeDesc color_type);

/// `image` as OpenImageIO's deep ImageBuf over its data window, to write
/// or to hand to a host, with the spec deep_result_spec() gives.
OIIO::ImageBuf deep_buffer(const DeepImage& image, const OIIO::ImageSpec& scene,
                           OIIO::TypeDesc color_type, int nthreads = 0);

}  // namespace defocus
