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
    /// The near fragment covers the pixel: the far one is not seen in it,
    /// but is the far surface continued behind the near one's edge.
    bool far_continued = false;
};

/// The mixed pixels of `flat`, ordered by row, then column. A pixel is
/// mixed where a neighbour's CoC differs from its own by more than a pixel
/// (less is no visible difference in blur): it carries the depth of one
/// side and may hold light of both. Its two sides' colours come from the
/// pixels of each side around it, and its colour is taken as a blend of
/// the two: the near side's coverage is the position of the colour on the
/// line between them (a two-colour matting model, as in Ruzon & Tomasi 2000
/// and Levin et al. 2008). A pixel whose sides have one colour, or whose
/// colour is no blend of them, is not split; where it carries the near
/// side's depth, it stays whole over the far surface continued behind it
/// from its nearest pixel, as a deep render holds it.
std::vector<MixedPixel> find_mixed_pixels(const Layer& flat, const CircleOfConfusion& coc,
                                          int nthreads = 0);

}  // namespace defocus
