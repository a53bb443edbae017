// The "layer setup" view: how a scene was cut into depth layers.
#pragma once

#include <Imath/ImathVec.h>
#include <OpenImageIO/imagebuf.h>

#include <defocus/layers/layered_scene.h>

namespace defocus {

/// The colour of layer `index` (back to front) in layer_view(): hues a
/// golden angle apart, so that neighbours in depth differ most.
Imath::V3f layer_colour(int index);

/// A false-colour RGBA image over the scene's display window, unblurred:
/// each layer its layer_colour(), composited back to front with "over" on
/// its alpha, so that a pixel split between layers mixes their colours by
/// coverage. Uncovered pixels are transparent. It shows a compositor where
/// edges were cut, as ZDefocus's layer setup does.
bool layer_view(OIIO::ImageBuf& dst, const LayeredScene& scene, int nthreads = 0);

}  // namespace defocus
