// Constant-time rectangle spreading: Kosloff, Tao & Barsky, "Depth of
// Field Postprocessing for Layered Scenes Using Constant-Time Rectangle
// Spreading", GI 2009, section 3, with fractional edge coverage.
#include <defocus/spread.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include <OpenImageIO/parallel.h>

#include "float_pixels.h"
#include "row_bands.h"
#include "spread_common.h"

namespace defocus {

ROI box_spread_extent(const ROI& roi, double max_coc_radius)
{
    const BoxEdges e = box_edges(box_half_width(max_coc_radius));
    return ROI(roi.xbegin + e.first, roi.xend + e.last, roi.ybegin + e.first,
               roi.yend + e.last, 0, 1, roi.chbegin, roi.chend);
}

namespace {

/// The 1-D edge deltas of a box: integrating them once gives the covered
/// length of each pixel (first_cover, 1, 1, ..., last_cover).
struct EdgeDeltas {
    int offset[4];
    double value[4];
};

EdgeDeltas edge_deltas(const BoxEdges& e, double scale)
{
    return { { e.first, e.first + 1, e.last, e.last + 1 },
             { scale * e.first_cover, scale * (1.0 - e.first_cover),
               scale * (e.last_cover - 1.0), -scale * e.last_cover } };
}

}  // namespace

bool spread_box(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius,
                ROI roi, int nthreads)
{
    const SpreadInputs in = prepare_spread(dst, src, radius, roi, nthreads);
    if (!in.valid)
        return false;
    const int nc = in.nchannels;
    roi = in.roi;
    const ROI ext = box_spread_extent(roi, in.max_radius);
    const int reach = box_edges(box_half_width(in.max_radius)).last + 1;

    // Deltas live in double: the prefix sums then stay within 1e-4 relative
    // on HDR data (values 1e-3..1e4), where float drifts by whole units
    // down a 2160-row column. The buffer has one extra row and column for
    // the closing deltas of the right- and bottom-most boxes.
    const int bw = ext.width() + 1, bh = ext.height() + 1;
    const size_t row_len = size_t(bw) * nc;
    std::unique_ptr<double[]> acc(new double[row_len * bh]);

    // Scatter the deltas, then integrate each row horizontally, band by
    // band: a band's rows are written only by the thread that owns it.
    for_each_row_band(0, bh, nthreads, [&](int r0, int r1) {
        std::fill(&acc[r0 * row_len], &acc[r1 * row_len], 0.0);
        const int ylo = std::max(roi.ybegin, ext.ybegin + r0 - reach);
        const int yhi = std::min(roi.yend, ext.ybegin + r1 + reach);
        for (int y = ylo; y < yhi; ++y) {
            const int by = y - ext.ybegin;
            for (int x = roi.xbegin; x < roi.xend; ++x) {
                const float* v = in.pixels(x, y);
                if (is_zero(v, nc))
                    continue;
                const double h     = box_half_width(*in.radii(x, y));
                const BoxEdges e   = box_edges(h);
                const EdgeDeltas dy = edge_deltas(e, 1.0 / (4.0 * h * h));
                const EdgeDeltas dx = edge_deltas(e, 1.0);
                const int bx = x - ext.xbegin;
                for (int j = 0; j < 4; ++j) {
                    const int row = by + dy.offset[j];
                    if (row < r0 || row >= r1 || dy.value[j] == 0.0)
                        continue;
                    double* out = &acc[row * row_len];
                    for (int i = 0; i < 4; ++i) {
                        const double w = dy.value[j] * dx.value[i];
                        double* p = out + size_t(bx + dx.offset[i]) * nc;
                        for (int c = 0; c < nc; ++c)
                            p[c] += w * v[c];
                    }
                }
            }
        }
        for (int row = r0; row < r1; ++row) {
            double* p = &acc[row * row_len];
            for (size_t k = nc; k < row_len; ++k)
                p[k] += p[k - nc];
        }
    });

    // Integrate vertically, column chunks in parallel, into float output.
    ImageSpec spec = output_spec(src, ext);
    dst.reset(spec);
    float* out = static_cast<float*>(dst.localpixels());
    const int64_t ow = ext.width(), oh = ext.height();
    OIIO::parallel_for_chunked(
        0, ow * nc, 0,
        [&](int64_t k0, int64_t k1) {
            std::vector<double> sum(k1 - k0, 0.0);
            for (int64_t y = 0; y < oh; ++y) {
                const double* a = &acc[y * row_len];
                float* o        = out + y * ow * nc;
                for (int64_t k = k0; k < k1; ++k) {
                    sum[k - k0] += a[k];
                    o[k] = float(sum[k - k0]);
                }
            }
        },
        OIIO::paropt(nthreads));
    return true;
}

}  // namespace defocus
