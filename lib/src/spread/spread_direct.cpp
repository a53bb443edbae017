// The direct spreading reference: O(r²) per pixel, kept for the tests.
#include <defocus/spread/spread.h>

#include <algorithm>
#include <memory>
#include <vector>

#include <OpenImageIO/parallel.h>

#include "spread/row_bands.h"
#include "spread/spread_common.h"
#include "util/float_pixels.h"

namespace defocus {

bool spread_direct(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius,
                   const Psf& psf, ROI roi, int nthreads)
{
    const SpreadInputs in = prepare_spread(dst, src, radius, roi, nthreads);
    if (!in.valid)
        return false;
    const int nc = in.nchannels;
    roi = in.roi;
    // Footprints grow with the radius, so the largest bounds them all.
    const Footprint widest = psf(in.max_radius);
    const ROI ext(roi.xbegin + widest.x0, roi.xend + widest.x0 + widest.width - 1,
                  roi.ybegin + widest.y0, roi.yend + widest.y0 + widest.height - 1,
                  0, 1, 0, nc);
    const int reach = std::max(-widest.y0, widest.y0 + widest.height);

    const size_t row_len = size_t(ext.width()) * nc;
    std::vector<double> acc(row_len * ext.height(), 0.0);
    for_each_row_band(ext.ybegin, ext.yend, nthreads, [&](int y0, int y1) {
        const int ylo = std::max(roi.ybegin, y0 - reach);
        const int yhi = std::min(roi.yend, y1 + reach);
        for (int y = ylo; y < yhi; ++y)
            for (int x = roi.xbegin; x < roi.xend; ++x) {
                const float* v = in.pixels(x, y);
                if (is_zero(v, nc))
                    continue;
                const Footprint fp = psf(*in.radii(x, y));
                for (int j = 0; j < fp.height; ++j) {
                    const int oy = y + fp.y0 + j;
                    if (oy < y0 || oy >= y1)
                        continue;
                    double* row = &acc[(oy - ext.ybegin) * row_len];
                    for (int i = 0; i < fp.width; ++i) {
                        double* p = row + size_t(x + fp.x0 + i - ext.xbegin) * nc;
                        const double w = fp.at(i, j);
                        for (int c = 0; c < nc; ++c)
                            p[c] += w * v[c];
                    }
                }
            }
    });

    dst.reset(output_spec(src, ext), OIIO::InitializePixels::No);  // every pixel is written below
    std::copy(acc.begin(), acc.end(), static_cast<float*>(dst.localpixels()));
    return true;
}

}  // namespace defocus
