// Internal: a seen pixel of a layer as the hidden-surface estimates read it.
#pragma once

#include <algorithm>

#include "util/float_pixels.h"

namespace defocus {

/// Pixel (x, y) of `color` and `depth`: premultiplied R, G, B, A and the
/// alpha-weighted depth (0 where nothing covers it). An infinite depth (a
/// sky) counts as 1e30, so that an estimate blended in with weight 0 adds
/// 0, not NaN.
inline void observe(const FloatPixels& color, const FloatPixels& depth, int x, int y,
                    float value[5])
{
    const float* c = color(x, y);
    std::copy(c, c + 4, value);
    value[4] = c[3] > 0.0f ? c[3] * std::min(*depth(x, y), 1e30f) : 0.0f;
}

}  // namespace defocus
