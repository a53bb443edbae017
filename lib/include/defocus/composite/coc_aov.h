// The CoC AOV: the signed blur of what each output pixel shows, for
// compositors who drive other blurs from the defocus.
#pragma once

#include <OpenImageIO/imagebuf.h>

#include <defocus/composite/defocus_layers.h>
#include <defocus/layers/layered_scene.h>

namespace defocus {

/// One channel, "coc", over `roi`: the signed CoC diameter in pixels
/// (negative in front of the focus) of the front-most layer whose spread
/// reaches each pixel (with coverage above 1/1000), the coverage-weighted
/// mean over that layer's pixels that reach it; 0 where none does. Each
/// layer is spread alone as defocus_layers() spreads it, less chromatic
/// aberration and the PSF image, which change colour, not reach.
bool coc_aov(OIIO::ImageBuf& dst, const LayeredScene& scene, const Camera& camera,
             const SpreadOptions& spread, const ApertureImages& images, OutputWindow window,
             OIIO::ROI roi, int nthreads = 0);

}  // namespace defocus
