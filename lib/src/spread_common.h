// Internal: what every spreading filter checks and shares.
#pragma once

#include <OpenImageIO/imagebuf.h>

#include "float_pixels.h"

namespace defocus {

using OIIO::ImageSpec;

inline bool is_zero(const float* v, int nc)
{
    for (int c = 0; c < nc; ++c)
        if (v[c] != 0.0f)
            return false;
    return true;
}

/// Validates the common inputs of a spreading filter and fills in a
/// default roi (src's data window). On failure sets dst's error.
bool check_spread_inputs(OIIO::ImageBuf& dst, const OIIO::ImageBuf& src,
                         const OIIO::ImageBuf& radius, OIIO::ROI& roi);

/// The largest CoC radius of a pixel that carries light (pixels that are
/// all zero spread nothing, whatever their radius), or a negative value
/// (with dst's error set) when one is infinite or absurdly large.
double max_radius(OIIO::ImageBuf& dst, const FloatPixels& pixels,
                  const FloatPixels& radii, int nthreads);

/// A float spec over `window` with src's channel names and alpha channel.
ImageSpec output_spec(const OIIO::ImageBuf& src, const OIIO::ROI& window);

}  // namespace defocus
