// Internal: the driver of the filters that spread every pixel on its own,
// O(footprint) per pixel: the direct reference and the cat's eye.
#pragma once

#include <algorithm>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <defocus/spread/footprint.h>

#include "spread/row_bands.h"
#include "spread/spread_common.h"

namespace defocus {

/// Rows and columns, relative to a pixel, that its footprint can write.
struct PixelReach {
    int first_column, last_column, first_row, last_row;
};

/// Spreads every pixel of src that carries light into an accumulator over
/// roi grown by reach_of(largest radius), in bands of destination rows
/// (one per thread, which scans every source row that can reach it: no
/// races): scatter(x, y, value, nchannels, radius, row), with row(oy) the
/// accumulator row of destination row oy indexed by absolute column, or
/// null outside the band. With `integrate` the rows hold deltas and are
/// prefix-summed along x; the accumulator has a column more than dst on
/// the right for the deltas that end a row. dst is float, over the grown
/// roi.
template<typename ReachOf, typename Scatter>
bool scatter_pixels(OIIO::ImageBuf& dst, const OIIO::ImageBuf& src, const OIIO::ImageBuf& radius,
                    OIIO::ROI roi, int nthreads, ReachOf&& reach_of, bool integrate,
                    Scatter&& scatter)
{
    const SpreadInputs in = prepare_spread(dst, src, radius, roi, nthreads);
    if (!in.valid)
        return false;
    const int nc = in.nchannels;
    roi = in.roi;
    const PixelReach reach = reach_of(in.max_radius);
    const OIIO::ROI ext(roi.xbegin + reach.first_column, roi.xend + reach.last_column,
                        roi.ybegin + reach.first_row, roi.yend + reach.last_row, 0, 1, 0, nc);
    const size_t row_len = size_t(ext.width() + 1) * nc;
    std::vector<double> acc(row_len * ext.height(), 0.0);
    for_each_row_band(ext.ybegin, ext.yend, nthreads, [&](int y0, int y1) {
        auto row = [&](int oy) -> double* {
            return oy < y0 || oy >= y1 ? nullptr
                                       : &acc[size_t(oy - ext.ybegin) * row_len]
                                             - ptrdiff_t(ext.xbegin) * nc;
        };
        const int first = std::max(roi.ybegin, y0 - reach.last_row);
        const int last = std::min(roi.yend, y1 - reach.first_row);
        for (int y = first; y < last; ++y)
            for (int x = roi.xbegin; x < roi.xend; ++x) {
                const float* v = in.pixels(x, y);
                if (!is_zero(v, nc))
                    scatter(x, y, v, nc, double(*in.radii(x, y)), row);
            }
        if (integrate)
            for (int y = y0; y < y1; ++y) {
                double* r = &acc[size_t(y - ext.ybegin) * row_len];
                for (size_t i = nc; i < row_len; ++i)
                    r[i] += r[i - nc];
            }
    });
    dst.reset(output_spec(src, ext), OIIO::InitializePixels::No);  // every pixel is written
    float* out = static_cast<float*>(dst.localpixels());
    for (int y = 0; y < ext.height(); ++y)
        for (size_t i = 0; i < size_t(ext.width()) * nc; ++i)
            *out++ = float(acc[size_t(y) * row_len + i]);
    return true;
}

/// The reach of a PSF's footprints up to the largest radius: footprints
/// grow with the radius, so the largest bounds them all.
inline PixelReach footprint_reach(const Psf& psf, double max_radius)
{
    const Footprint widest = psf(max_radius);
    return { widest.x0, widest.x0 + widest.width - 1, widest.y0, widest.y0 + widest.height - 1 };
}

/// Adds a pixel's footprint times its value to the accumulator rows.
template<typename Row>
void add_footprint(const Footprint& fp, int x, int y, const float* v, int nc, Row&& row)
{
    for (int j = 0; j < fp.height; ++j)
        if (double* out = row(y + fp.y0 + j))
            for (int i = 0; i < fp.width; ++i)
                for (int c = 0; c < nc; ++c)
                    out[ptrdiff_t(x + fp.x0 + i) * nc + c] += fp.at(i, j) * v[c];
}

}  // namespace defocus
