// Internal: what spreading a frame holds, as the memory limit counts it.
#pragma once

#include <defocus/layers/layered_scene.h>
#include <defocus/optics/camera.h>
#include <defocus/shot/options.h>

namespace defocus {

/// What spreading holds besides the layers: the image a frame is spread
/// into and its accumulator, float RGBA each, over `pixels`.
double result_bytes(double pixels);

/// A bound on what spreading the layers as `spread` says holds at once:
/// each layer's buffers (colour, depth, the rebuilt plane of a sliced
/// render) grown by its blur's reach, with its blur field and highlight
/// mask; the result and an accumulator over all of them; the holdout; and
/// where the aperture may be cut into cells, what compositing per cell
/// holds through `camera` (a set of cells for each CoC of its colours), on
/// `nthreads` threads (0: all).
double spread_bytes(const LayeredScene& layered, const SpreadOptions& spread,
                    const Camera& camera, int nthreads);

}  // namespace defocus
