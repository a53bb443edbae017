// Internal: how bright a pixel counts where the hidden-background fill
// weighs highlights.
#pragma once

#include <algorithm>

namespace defocus {

/// (R + G + B) / 3 of premultiplied RGBA, at least 0.
inline float brightness(const float* rgba)
{
    return std::max(0.0f, (rgba[0] + rgba[1] + rgba[2]) / 3.0f);
}

}  // namespace defocus
