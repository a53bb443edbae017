// The pixels of a flat render that mix two surfaces at a depth
// discontinuity, split into their two surfaces.
#pragma once

#include <vector>

#include <defocus/scene.h>
#include <defocus/optics/camera.h>

namespace defocus {

/// One mixed pixel as two surfaces. A renderer writes one depth per pixel,
/// so an antialiased pixel on the silhouette of an object holds the colour
/// of both sides under the depth of one: spread whole, an in-focus light's
/// rim written at the far background's depth grows a bokeh disc the lens
/// never makes. Two fragments, premultiplied colour and coverage, as deep
/// samples: `near` at `near_z` over `far` at `far_z` gives back the pixel.
struct MixedPixel {
    int x, y;
    float near[4], far[4];
    float near_z, far_z;
};

/// The mixed pixels of `flat`, ordered by row, then column. A pixel is
/// mixed where a nearer neighbour's CoC differs from its own by more than
/// a pixel (less is no visible difference in blur): it carries the far
/// side's depth and some of the near side's light. Its two sides' colours are the
/// means of the unmixed pixels of each side around it, and its colour is
/// taken as a blend of the two: the near side's coverage is the position
/// of the colour on the line between them (a two-colour matting model, as
/// in Ruzon & Tomasi 2000 and Levin et al. 2008). A pixel whose sides have
/// one colour is left whole: a split would change nothing one could see.
std::vector<MixedPixel> find_mixed_pixels(const Layer& flat, const CircleOfConfusion& coc,
                                          int nthreads = 0);

}  // namespace defocus
