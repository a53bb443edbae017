// Smooth PSFs in constant time by repeated integration (Heckbert 1986,
// "Filtering by repeated integration"; Kosloff, Hensley & Barsky 2009,
// "Fast filter spreading"). The order-n PSF is n boxes convolved: per axis
// its n-th difference is the binomial delta set (δ0 - δw)^n, so each pixel
// writes (n+1)² deltas (per blended width) and the buffer is integrated n
// times along x and n times along y.
//
// The integration is exact: deltas are fixed-point integers in 128 bits
// and the sums wrap around, which is exact modulo 2^128, so the rounding
// residue that floating point would leave after one integration, and the
// next integrations would amplify into a ramp, never appears.
#include <defocus/spread/spread.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>

#include <immintrin.h>

#include <OpenImageIO/parallel.h>

#include "spread/row_bands.h"
#include "spread/spread_common.h"
#include "util/fresh_array.h"
#include "util/fresh_image.h"
#include "util/parallel_rows.h"

namespace defocus {

namespace {

using Fixed = unsigned __int128;
constexpr double fixed_scale = 79228162514264337593543950336.0;  // 2^96

/// The two integer box widths whose blend gives the PSF of CoC radius r,
/// and the blend. The order-n box of width w has variance n(w² - 1)/12;
/// matching the CoC disc's r²/4 gives w² = 1 + 3r²/n. Odd orders need odd
/// widths to stay centred.
struct Widths {
    int w[2];
    double weight[2];
};

Widths smooth_widths(int order, double r)
{
    const double w = std::sqrt(1.0 + 3.0 * r * r / order);
    const int step = order % 2 ? 2 : 1;
    int w0 = std::max(1, int(std::floor(w)));
    if (step == 2 && w0 % 2 == 0)
        --w0;
    const double t = std::clamp((w - w0) / step, 0.0, 1.0);
    return { { w0, w0 + step }, { 1.0 - t, t } };
}

int binomial(int n, int k)
{
    int c = 1;
    for (int i = 0; i < k; ++i)
        c = c * (n - i) / (i + 1);
    return c;
}

/// The half-width of the order-n box of width w: n(w - 1)/2.
int half_support(int order, int w) { return order * (w - 1) / 2; }

/// One axis of the order-n box of width w, normalised: the taps from
/// -half_support to +half_support.
std::vector<double> box_power(int order, int w)
{
    std::vector<double> taps { 1.0 };
    for (int k = 0; k < order; ++k) {
        std::vector<double> next(taps.size() + w - 1, 0.0);
        for (size_t i = 0; i < taps.size(); ++i)
            for (int j = 0; j < w; ++j)
                next[i + j] += taps[i] / w;
        taps = std::move(next);
    }
    return taps;
}

}  // namespace

Footprint smooth_footprint(int order, double coc_radius)
{
    const Widths ws = smooth_widths(order, coc_radius);
    const int reach = half_support(order, ws.w[1]);
    std::vector<double> axis(2 * reach + 1, 0.0);
    for (int b = 0; b < 2; ++b) {
        const std::vector<double> taps = box_power(order, ws.w[b]);
        const int h = half_support(order, ws.w[b]);
        for (int i = -h; i <= h; ++i)
            axis[i + reach] += ws.weight[b] * taps[i + h];
    }
    Footprint fp;
    fp.x0 = fp.y0 = -reach;
    fp.width = fp.height = 2 * reach + 1;
    fp.weights.resize(size_t(fp.width) * fp.height);
    for (int j = 0; j < fp.height; ++j)
        for (int i = 0; i < fp.width; ++i)
            fp.weights[size_t(j) * fp.width + i] = axis[i] * axis[j];
    return fp;
}

namespace {

/// x (|x| < 2^127) rounded to the nearest integer, ties to even (as
/// nearbyint), as a 128-bit integer, without library calls: below 2^62 one
/// conversion instruction rounds it; above, it is an integer already, its
/// 53-bit mantissa shifted by its exponent.
Fixed to_fixed(double x)
{
    const double m = std::abs(x);
    Fixed f;
    if (m < 0x1p62) {
        f = Fixed(uint64_t(_mm_cvtsd_si64(_mm_set_sd(m))));
    } else {
        uint64_t bits;
        std::memcpy(&bits, &m, sizeof bits);
        const int exponent = int(bits >> 52) - 1075;  // m = mantissa 2^exponent
        const uint64_t mantissa = (bits & ((uint64_t(1) << 52) - 1)) | (uint64_t(1) << 52);
        f = Fixed(mantissa) << exponent;
    }
    return x < 0.0 ? -f : f;
}

/// x times n, a binomial of order at most 3 (1, 2 or 3): by additions,
/// cheaper than a 128-bit multiplication.
Fixed times(Fixed x, int n)
{
    Fixed sum = x;
    for (int i = 1; i < n; ++i)
        sum += x;
    return sum;
}

/// How a pixel of one radius is spread: its two widths and the amplitude
/// of each of its four separable pieces (x width a, y width b) per unit of
/// value, 0 for a piece of no weight.
struct SmoothPieces {
    Widths ws;
    double scale[2][2];

    SmoothPieces(int order, double r)
        : ws(smooth_widths(order, r))
    {
        for (int a = 0; a < 2; ++a)
            for (int b = 0; b < 2; ++b) {
                double power = 1.0;  // (w_a w_b)^order, exact
                for (int k = 0; k < order; ++k)
                    power *= double(ws.w[a]) * double(ws.w[b]);
                scale[a][b] = ws.weight[a] * ws.weight[b] / power;
            }
    }
};

/// The accumulation buffer of spread_smooth: rows of `ext`, `nc` fixed-point
/// channels a pixel.
struct SmoothAccumulator {
    ROI ext;
    int nc, order;
    size_t row_len;
    std::unique_ptr<Fixed[]> acc;
    int binomials[4];  ///< of `order` (at most 3), by k: made once, they divide

    SmoothAccumulator(const ROI& ext, int nc, int order, int nthreads)
        : ext(ext), nc(nc), order(order), row_len(size_t(ext.width()) * nc)
        , acc(fresh_array<Fixed>(row_len * ext.height(), nthreads))
    {
        for (int k = 0; k <= order; ++k)
            binomials[k] = binomial(order, k);
    }

    /// Pixel (x, y)'s value `v` as the corner deltas of its four
    /// separable pieces (widths `ws`), those in rows [r0, r1). Deltas
    /// beyond the right edge only reach further out: dropped.
    void scatter(int x, int y, const float* v, const SmoothPieces& pieces, int r0, int r1)
    {
        const Widths& ws = pieces.ws;
        for (int a = 0; a < 2; ++a)
            for (int b = 0; b < 2; ++b) {
                const double scale = pieces.scale[a][b];
                if (scale == 0.0)
                    continue;
                Fixed amplitude[8];
                for (int c = 0; c < nc; ++c)
                    amplitude[c] = to_fixed(double(v[c]) * scale * fixed_scale);
                for (int k = 0; k <= order; ++k) {
                    const int row = y - ext.ybegin - half_support(order, ws.w[b]) + k * ws.w[b];
                    if (row < r0 || row >= r1)
                        continue;
                    const int ck = (k % 2 ? -1 : 1) * binomials[k];
                    for (int l = 0; l <= order; ++l) {
                        const int col = x - ext.xbegin - half_support(order, ws.w[a]) + l * ws.w[a];
                        if (col >= ext.width())
                            continue;
                        const __int128 coef = __int128(ck) * ((l % 2 ? -1 : 1) * binomials[l]);
                        Fixed* p = &acc[row * row_len + size_t(col) * nc];
                        for (int c = 0; c < nc; ++c)
                            p[c] += amplitude[c] * Fixed(coef);
                    }
                }
            }
    }

    /// Pixels [x0, x1) of source row y, all of one pair of widths: each
    /// piece's column deltas are gathered on a line first, then added to
    /// the piece's rows (those in [r0, r1)) scaled by their row binomial.
    /// The same sums as scatter() pixel by pixel, but each row is written
    /// once, along its length, not at every pixel's columns: the deltas of
    /// a long run stay in cache.
    void scatter_run(int x0, int x1, int y, const SpreadInputs& in, int r0, int r1,
                     std::vector<Fixed>& line)
    {
        float radius = NAN;
        SmoothPieces pieces(order, 0.0);
        const Widths ws = smooth_widths(order, *in.radii(x0, y));
        for (int b = 0; b < 2; ++b) {
            const int row0 = y - ext.ybegin - half_support(order, ws.w[b]);
            const int first_k = r0 > row0 ? (r0 - row0 + ws.w[b] - 1) / ws.w[b] : 0;
            if (first_k > order || row0 + first_k * ws.w[b] >= r1)
                continue;
            int lo = ext.width(), hi = 0;  // the line's cells written
            for (int x = x0; x < x1; ++x) {
                if (*in.radii(x, y) != radius) {
                    radius = *in.radii(x, y);
                    pieces = SmoothPieces(order, radius);
                }
                const float* v = in.pixels(x, y);
                for (int a = 0; a < 2; ++a) {
                    const double scale = pieces.scale[a][b];
                    if (scale == 0.0)
                        continue;
                    const int col0 = x - ext.xbegin - half_support(order, ws.w[a]);
                    lo = std::min(lo, col0);
                    hi = std::max(hi, std::min(ext.width(), col0 + order * ws.w[a] + 1));
                    for (int c = 0; c < nc; ++c) {
                        const Fixed amplitude =
                            to_fixed(double(v[c]) * scale * fixed_scale);
                        for (int l = 0; l <= order; ++l) {
                            const int col = col0 + l * ws.w[a];
                            if (col >= ext.width())
                                break;
                            const Fixed d = times(amplitude, binomials[l]);
                            Fixed& cell = line[size_t(col) * nc + c];
                            cell = l % 2 ? cell - d : cell + d;
                        }
                    }
                }
            }
            if (lo >= hi)  // every pixel's piece of weight 0
                continue;
            for (int k = first_k; k <= order && row0 + k * ws.w[b] < r1; ++k) {
                Fixed* row = &acc[size_t(row0 + k * ws.w[b]) * row_len];
                const bool subtract = k % 2;
                for (size_t i = size_t(lo) * nc; i < size_t(hi) * nc; ++i) {
                    const Fixed d = times(line[i], binomials[k]);
                    row[i] = subtract ? row[i] - d : row[i] + d;
                }
            }
            std::fill(line.begin() + ptrdiff_t(lo) * nc, line.begin() + ptrdiff_t(hi) * nc,
                      Fixed(0));
        }
    }

    /// Each of rows [r0, r1) integrated `order` times.
    void integrate_rows(int r0, int r1)
    {
        for (int row = r0; row < r1; ++row) {
            Fixed* p = &acc[row * row_len];
            for (int pass = 0; pass < order; ++pass)
                for (size_t k = nc; k < row_len; ++k)
                    p[k] += p[k - nc];
        }
    }

    /// Each column integrated `order` times, in column chunks, into float.
    void integrate_columns(float* out, int nthreads) const
    {
        OIIO::parallel_for_chunked(0, int64_t(row_len), 0, [&](int64_t k0, int64_t k1) {
            std::vector<Fixed> sums(size_t(k1 - k0) * order, Fixed(0));
            for (int64_t y = 0; y < ext.height(); ++y) {
                const Fixed* a = &acc[y * row_len];
                float* o = out + y * row_len;
                for (int64_t k = k0; k < k1; ++k) {
                    Fixed* s = &sums[size_t(k - k0) * order];
                    s[0] += a[k];
                    for (int pass = 1; pass < order; ++pass)
                        s[pass] += s[pass - 1];
                    o[k] = float(double(__int128(s[order - 1])) / fixed_scale);
                }
            }
        }, by_rows(nthreads));
    }
};

}  // namespace

bool spread_smooth(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius, int order,
                   ROI roi, int nthreads)
{
    if (order < 2 || order > 3) {
        dst.errorfmt("spread_smooth: order {} (2: tent, 3: smooth)", order);
        return false;
    }
    const SpreadInputs in = prepare_spread(dst, src, radius, roi, nthreads);
    if (!in.valid)
        return false;
    const int nc = in.nchannels;
    if (nc > 8) {
        dst.errorfmt("spread_smooth: {} channels (at most 8)", nc);
        return false;
    }
    roi = in.roi;
    const int reach = half_support(order, smooth_widths(order, in.max_radius).w[1]);
    SmoothAccumulator acc(ROI(roi.xbegin - reach, roi.xend + reach, roi.ybegin - reach,
                              roi.yend + reach, 0, 1, 0, nc),
                          nc, order, nthreads);
    const ROI& ext = acc.ext;

    // Scatter, then integrate each row `order` times, band by band. Deltas
    // beyond the bottom edge only reach further out: dropped.
    for_each_row_band(0, ext.height(), nthreads, [&](int r0, int r1) {
        std::fill(&acc.acc[r0 * acc.row_len], &acc.acc[r1 * acc.row_len], Fixed(0));
        // A source row writes rows from y - half to y + half + order.
        const int ylo = std::max(roi.ybegin, ext.ybegin + r0 - reach - order);
        const int yhi = std::min(roi.yend, ext.ybegin + r1 + reach);
        // Neighbours mostly share a radius: its pieces made once per change.
        float radius = NAN;
        SmoothPieces pieces(order, 0.0);
        std::vector<Fixed> line(acc.row_len, Fixed(0));
        for (int y = ylo; y < yhi; ++y)
            for (int x = roi.xbegin; x < roi.xend;) {
                const float* v = in.pixels(x, y);
                if (is_zero(v, nc)) {
                    ++x;
                    continue;
                }
                // A run of lit pixels of one pair of widths at least half
                // a footprint long goes by lines.
                if (*in.radii(x, y) != radius) {
                    radius = *in.radii(x, y);
                    pieces = SmoothPieces(order, radius);
                }
                const int w0 = pieces.ws.w[0];
                int end = x + 1;
                while (end < roi.xend && !is_zero(in.pixels(end, y), nc)
                       && (*in.radii(end, y) == radius
                           || smooth_widths(order, *in.radii(end, y)).w[0] == w0))
                    ++end;
                if (2 * (end - x) >= half_support(order, w0 + 2)) {
                    acc.scatter_run(x, end, y, in, r0, r1, line);
                    x = end;
                    continue;
                }
                for (; x < end; ++x) {
                    if (*in.radii(x, y) != radius) {
                        radius = *in.radii(x, y);
                        pieces = SmoothPieces(order, radius);
                    }
                    acc.scatter(x, y, in.pixels(x, y), pieces, r0, r1);
                }
            }
        acc.integrate_rows(r0, r1);
    });

    reset_for_overwrite(dst, output_spec(src, ext), nthreads);  // every pixel is written below
    acc.integrate_columns(static_cast<float*>(dst.localpixels()), nthreads);
    return true;
}

}  // namespace defocus
