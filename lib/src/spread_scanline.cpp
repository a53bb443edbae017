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

namespace {

/// A span as four horizontal deltas, relative to the source pixel's column.
struct EdgeDeltas {
    int row;
    int column[4];
    double weight[4];
};

void edge_deltas(const RowProfile& profile, double r, std::vector<RowSpan>& spans,
                 std::vector<EdgeDeltas>& deltas)
{
    const double area = profile.rows(r, spans);
    deltas.clear();
    for (const RowSpan& s : spans) {
        // The pixel's centre is at +0.5 from its column.
        const double a = 0.5 + s.left, b = 0.5 + s.right;
        const double ia = std::floor(a), ib = std::floor(b);
        const double fa = a - ia, fb = b - ib;
        const double scale = s.weight / area;
        deltas.push_back({ s.row,
                           { int(ia), int(ia) + 1, int(ib), int(ib) + 1 },
                           { (1.0 - fa) * scale, fa * scale, -(1.0 - fb) * scale, -fb * scale } });
    }
}

/// Adds one pixel's deltas to its rows within [r0, r1). With four channels
/// a delta is one 256-bit multiply-add where the CPU has AVX2, chosen when
/// the program starts (the binary still runs on any x86-64).
__attribute__((target_clones("avx2", "default")))
void add_deltas_rgba(const std::vector<EdgeDeltas>& deltas, const float* v, double* acc,
                     size_t row_len, int bx, int by, int r0, int r1)
{
    const double v0 = v[0], v1 = v[1], v2 = v[2], v3 = v[3];
    for (const EdgeDeltas& d : deltas) {
        const int row = by + d.row;
        if (row < r0 || row >= r1)
            continue;
        double* out = acc + row * row_len;
        for (int i = 0; i < 4; ++i) {
            double* p = out + size_t(bx + d.column[i]) * 4;
            const double w = d.weight[i];
            p[0] += w * v0;
            p[1] += w * v1;
            p[2] += w * v2;
            p[3] += w * v3;
        }
    }
}

}  // namespace

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

    // Column tiles keep the rows a tile's pixels write (2·reach + 1 of
    // them) in cache while the tile is scattered.
    const int tile = 192;
    for_each_row_band(0, ext.height(), nthreads, [&](int r0, int r1) {
        std::fill(&acc[r0 * row_len], &acc[r1 * row_len], 0.0);
        // A span's edge weights and column offsets depend on the radius
        // only (pixel centres are whole columns apart), so they are worked
        // out once per radius; neighbouring pixels mostly share one.
        std::vector<RowSpan> spans;
        std::vector<EdgeDeltas> deltas;
        float spans_radius = -1.0f;
        const int ylo = std::max(roi.ybegin, ext.ybegin + r0 - reach);
        const int yhi = std::min(roi.yend, ext.ybegin + r1 + reach);
        for (int x0 = roi.xbegin; x0 < roi.xend; x0 += tile)
            for (int y = ylo; y < yhi; ++y)
                for (int x = x0; x < std::min(x0 + tile, roi.xend); ++x) {
                    const float* v = in.pixels(x, y);
                    if (is_zero(v, nc))
                        continue;
                    const float r = *in.radii(x, y);
                    if (r != spans_radius) {
                        edge_deltas(profile, r, spans, deltas);
                        spans_radius = r;
                    }
                    const int bx = x - ext.xbegin, by = y - ext.ybegin;
                    if (nc == 4) {
                        add_deltas_rgba(deltas, v, acc.get(), row_len, bx, by, r0, r1);
                        continue;
                    }
                    for (const EdgeDeltas& d : deltas) {
                        const int row = by + d.row;
                        if (row < r0 || row >= r1)
                            continue;
                        double* out = &acc[row * row_len];
                        for (int i = 0; i < 4; ++i) {
                            double* p = out + size_t(bx + d.column[i]) * nc;
                            for (int c = 0; c < nc; ++c)
                                p[c] += d.weight[i] * v[c];
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
