// Spreading arbitrary constant-intensity shapes scanline by scanline:
// Kosloff, Tao & Barsky 2009, section 4.1. Each row of a pixel's footprint
// is an interval written as edge deltas (with fractional coverage) and the
// rows are integrated horizontally once, so a pixel costs its footprint's
// height, not its area.
#include <defocus/spread.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include <OpenImageIO/parallel.h>

#include "row_bands.h"
#include "spread_common.h"

namespace defocus {

bool spread_scanline(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius,
                     const RowProfile& profile, ROI roi, int nthreads)
{
    const SpreadInputs in = prepare_spread(dst, src, radius, roi, nthreads);
    if (!in.valid)
        return false;
    const int nc = in.nchannels;
    roi = in.roi;
    const int reach = profile.reach();
    const ROI ext(roi.xbegin - reach, roi.xend + reach, roi.ybegin - reach,
                  roi.yend + reach, 0, 1, 0, nc);
    // Deltas in double, for the same reason as the rectangle's; one extra
    // column takes the closing deltas of the right-most intervals.
    const size_t row_len = size_t(ext.width() + 1) * nc;
    std::unique_ptr<double[]> acc(new double[row_len * ext.height()]);

    for_each_row_band(0, ext.height(), nthreads, [&](int r0, int r1) {
        std::fill(&acc[r0 * row_len], &acc[r1 * row_len], 0.0);
        // Neighbouring pixels mostly share a radius: their spans are reused.
        std::vector<RowSpan> spans;
        float spans_radius = -1.0f;
        double area = 0.0;
        const int ylo = std::max(roi.ybegin, ext.ybegin + r0 - reach);
        const int yhi = std::min(roi.yend, ext.ybegin + r1 + reach);
        for (int y = ylo; y < yhi; ++y)
            for (int x = roi.xbegin; x < roi.xend; ++x) {
                const float* v = in.pixels(x, y);
                if (is_zero(v, nc))
                    continue;
                const float r = *in.radii(x, y);
                if (r != spans_radius) {
                    area = profile.rows(r, spans);
                    spans_radius = r;
                }
                const double centre = x - ext.xbegin + 0.5;
                for (const RowSpan& s : spans) {
                    const int row = y - ext.ybegin + s.row;
                    if (row < r0 || row >= r1)
                        continue;
                    double* out = &acc[row * row_len];
                    const double a = centre + s.left, b = centre + s.right;
                    const double ia = std::floor(a), ib = std::floor(b);
                    const double fa = a - ia, fb = b - ib;
                    const int col[4] = { int(ia), int(ia) + 1, int(ib), int(ib) + 1 };
                    const double scale = s.weight / area;
                    const double w[4] = { (1.0 - fa) * scale, fa * scale,
                                          -(1.0 - fb) * scale, -fb * scale };
                    for (int i = 0; i < 4; ++i) {
                        double* p = out + size_t(col[i]) * nc;
                        for (int c = 0; c < nc; ++c)
                            p[c] += w[i] * v[c];
                    }
                }
            }
        for (int row = r0; row < r1; ++row) {
            double* p = &acc[row * row_len];
            for (size_t k = nc; k < row_len; ++k)
                p[k] += p[k - nc];
        }
    });

    dst.reset(output_spec(src, ext));
    float* out = static_cast<float*>(dst.localpixels());
    const size_t out_len = size_t(ext.width()) * nc;
    OIIO::parallel_for(0, ext.height(), [&](int row) {
        std::copy(&acc[row * row_len], &acc[row * row_len] + out_len, out + row * out_len);
    }, OIIO::paropt(nthreads));
    return true;
}

}  // namespace defocus
