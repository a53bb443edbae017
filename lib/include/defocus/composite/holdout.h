// Holdouts: the other elements of a shot, as a deep image, which cut the
// defocused element where they stand in front of it, as deep compositing
// holds an element out. A holdout is not defocused and is not part of the
// output, so that the element can be merged with the others later, each
// with its own defocus.
#pragma once

#include <OpenImageIO/imagebuf.h>

#include <defocus/scene.h>

namespace defocus {

/// All of `scene` as one deep image over the union of its windows, each
/// pixel's samples sorted front to back: deep samples as they are, and
/// each pixel of a layer or flat render as one sample at its Z with its
/// alpha. Only depth and alpha matter to a holdout; colour is kept as read.
DeepImage holdout_image(const Scene& scene);

/// The fraction of light from behind that passes the holdout's samples
/// lying between depths `near` and `far` at pixel (x, y) (1 outside its
/// window). A volume sample (zback > z) counts for the part of it inside
/// [near, far), split as OpenEXR's deep compositing splits samples: a part
/// f of it has alpha 1 - (1 - alpha)^f.
double holdout_transmittance(const DeepImage& holdout, int x, int y, double near, double far);

/// Scales the premultiplied RGBA of `frame` over `roi` by the holdout's
/// transmittance between `near` and `far`: what lies behind `far` and is
/// composited already is cut by the holdout in front of it up to `near`.
void hold_out(OIIO::ImageBuf& frame, const DeepImage& holdout, double near, double far,
              OIIO::ROI roi, int nthreads = 0);

}  // namespace defocus
