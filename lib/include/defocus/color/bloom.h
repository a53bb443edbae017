// Bloom: clipped highlights of a display-referred plate made bright again.
#pragma once

#include <cstdint>

#include <defocus/scene.h>

namespace defocus {

/// A plate encoded for display (an sRGB PNG, a JPEG, a Rec.709 video
/// frame) clips its highlights at white: spread as they are, a street
/// lamp's bokeh is as dim as the wall beside it. Bloom, as ZDefocus's and
/// Foundry Bokeh's lens bloom, multiplies light above `threshold` by `gain`
/// before spreading.
struct Bloom {
    double threshold = 1.0;
    double gain = 1.0;

    /// What a surface of colour (r, g, b), unpremultiplied, is multiplied
    /// by: `gain` from its brightest channel at the threshold up, 1 below
    /// 0.9 times it, and a smoothstep between, so that no edge steps.
    double factor(double r, double g, double b) const;
};

/// Multiplies the colour of every layer and flat render pixel and every
/// deep sample of `scene` (in the spreading space: scene-linear) by
/// `bloom`'s factor; returns how many pixels and samples it lifted.
int64_t apply_bloom(Scene& scene, const Bloom& bloom, int nthreads = 0);

}  // namespace defocus
