// Internal: what every spreading filter checks and shares.
#pragma once

#include <OpenImageIO/imagebuf.h>

#include <defocus/spread/cateye.h>
#include <defocus/spread/hybrid.h>

#include "spread/spread_engine.h"
#include "util/float_pixels.h"

namespace defocus {

using OIIO::ImageSpec;

inline bool is_zero(const float* v, int nc)
{
    for (int c = 0; c < nc; ++c)
        if (v[c] != 0.0f)
            return false;
    return true;
}

/// The validated inputs of a spreading filter as float views.
struct SpreadInputs {
    bool valid = false;
    OIIO::ROI roi;  ///< the region of src to spread
    int nchannels = 0;
    FloatPixels pixels, radii;
    double max_radius = 0;  ///< over the pixels that carry light
};

/// Checks the inputs of a spreading filter (filling in a default roi: src's
/// data window) and finds the largest radius of a pixel that carries light:
/// all-zero pixels spread nothing, whatever their radius. On failure sets
/// dst's error and returns an invalid SpreadInputs.
SpreadInputs prepare_spread(OIIO::ImageBuf& dst, const OIIO::ImageBuf& src,
                            const OIIO::ImageBuf& radius, OIIO::ROI roi,
                            int nthreads);

/// A float spec over `window` with src's channel names and alpha channel.
ImageSpec output_spec(const OIIO::ImageBuf& src, const OIIO::ROI& window);

/// Spreads src (at most 4 channels) into dst, a float image over every
/// pixel the spread lights, with the engine `method`; `shape` for the
/// shape methods, clipped by `cateye` when its amount is not 0. The pixels
/// that pass `highlights` (see visible_bokeh) are never merged into blocks.
/// The box's rectangles are `box_aspect` times as wide as tall.
bool spread_image(OIIO::ImageBuf& dst, const OIIO::ImageBuf& src, const OIIO::ImageBuf& radius,
                  OIIO::ROI roi, int nthreads, SpreadMethod method,
                  const RowProfile* shape = nullptr, const HighlightTest& highlights = {},
                  const CatEye& cateye = {}, double box_aspect = 1.0);

}  // namespace defocus
