// Smooth PSFs in constant time by repeated integration (Heckbert 1986,
// "Filtering by repeated integration"; Kosloff, Hensley & Barsky 2009,
// "Fast filter spreading"). The order-n PSF is n boxes convolved: per axis
// its n-th difference is the binomial delta set (δ0 - δw)^n. Down the
// columns, what a source row adds to the layer is written as n+1 delta
// rows, and the rows are integrated n times.
//
// Along a row, a run of pixels that share their pair of box widths (a
// plane, a sky: most of a layer) is filtered directly, by n running box
// sums in double precision for each width. A running sum adds each value
// once and takes it away once, so its rounding does not grow along the
// row. The run's row profile is then rounded once to 64-bit fixed point,
// and the integration down the columns is exact: integer sums wrap around,
// exact modulo 2^64, so no rounding residue is left for the next
// integrations to amplify into a ramp across the frame. Rounding the
// profile rather than each pixel's deltas costs a precision of w^n (one
// axis) rather than w^2n, which is what lets 64 bits do.
//
// A pixel in a run too short to pay for its profile's width is written as
// the (n+1)² corner deltas of its pieces instead, in 128-bit fixed point
// (the w^2n needs it), integrated n times along x and then down the
// columns with the rest: constant time per pixel. A band of rows makes
// each buffer only if it has pixels of that kind.
#include <defocus/spread/spread.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <type_traits>
#include <vector>

#include <immintrin.h>

#include <OpenImageIO/parallel.h>

#include "spread/row_bands.h"
#include "spread/spread_common.h"
#include "util/fresh_array.h"
#include "util/fresh_image.h"
#include "util/parallel_rows.h"
#include "util/simd.h"

namespace defocus {

namespace {

using Fixed = unsigned __int128;
constexpr double fixed_scale = 0x1p96;

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

/// The largest magnitude of a channel over the pixels spread.
double largest_magnitude(const SpreadInputs& in, int nthreads)
{
    std::mutex mutex;
    double largest = 0.0;
    const size_t row_values = size_t(in.roi.width()) * in.nchannels;
    OIIO::parallel_for_chunked(in.roi.ybegin, in.roi.yend, 0, [&](int64_t y0, int64_t y1) {
        float most = 0.0f;
        for (int64_t y = y0; y < y1; ++y) {
            const float* p = in.pixels(in.roi.xbegin, int(y));
            for (size_t i = 0; i < row_values; ++i)
                most = std::max(most, std::abs(p[i]));
        }
        std::lock_guard<std::mutex> lock(mutex);
        largest = std::max(largest, double(most));
    }, by_rows(nthreads));
    return largest;
}

/// The scale of the profiles' 64-bit fixed point: a power of two, exact to
/// apply, under which a pixel's spread sum stays below 2^62 even where
/// the PSFs of 2^7 pixels of the largest value peak on it (PSFs of
/// different radii can stack to about 2π ln(width) at one pixel). The
/// rounding of a profile is then 2^-56 of that value, times w^order once
/// integrated down the columns: 2^-32 for smooth at radius 256.
double profile_scale(double largest)
{
    int exponent = 0;
    std::frexp(largest, &exponent);  // largest < 2^exponent
    return std::ldexp(1.0, 55 - exponent);
}

using double8 = double __attribute__((vector_size(64)));

/// One running box sum of width w over `len` pixels of NC channels: dst
/// (len + w - 1 pixels) at i is the sum of src from i - w + 1 to i, added
/// to dst with `accumulate`. A running sum adds each value once and takes
/// it away once: its rounding error does not grow with the run, unlike
/// the integration of deltas.
template<int NC>
DEFOCUS_KERNEL void running_box(const double* src, int len, int w, double* dst, bool accumulate)
{
    // All channels in one vector, so that the sum stays in a register.
    using Lanes = std::conditional_t<(NC <= 4), double4, double8>;
    constexpr size_t bytes = NC * sizeof(double);
    Lanes sum = {}, added = {}, taken = {}, had = {};
    for (int i = 0; i < len + w - 1; ++i) {
        if (i < len) {
            std::memcpy(&added, src + size_t(i) * NC, bytes);
            sum += added;
        }
        if (i >= w) {
            std::memcpy(&taken, src + size_t(i - w) * NC, bytes);
            sum -= taken;
        }
        double* out = dst + size_t(i) * NC;
        if (accumulate) {
            std::memcpy(&had, out, bytes);
            had += sum;
            std::memcpy(out, &had, bytes);
        } else {
            std::memcpy(out, &sum, bytes);
        }
    }
}

/// Adds to `profile` the order-`order` box power of width w of `values`
/// (len pixels of NC channels): len + order (w - 1) pixels, by `order`
/// running sums.
template<int NC>
DEFOCUS_KERNEL void add_box_power(const double* values, int len, int order, int w,
                                  double* profile, std::vector<double>& work)
{
    const size_t most = size_t(len + order * (w - 1)) * NC;
    work.resize(2 * most);
    const double* src = values;
    for (int pass = 0; pass < order; ++pass) {
        double* dst = pass == order - 1 ? profile : work.data() + (pass % 2) * most;
        running_box<NC>(src, len, w, dst, pass == order - 1);
        src = dst;
        len += w - 1;
    }
}

DEFOCUS_CLONES
void add_box_power(const double* values, int len, int nc, int order, int w, double* profile,
                   std::vector<double>& work)
{
    switch (nc) {
    case 1: return add_box_power<1>(values, len, order, w, profile, work);
    case 2: return add_box_power<2>(values, len, order, w, profile, work);
    case 3: return add_box_power<3>(values, len, order, w, profile, work);
    case 4: return add_box_power<4>(values, len, order, w, profile, work);
    case 5: return add_box_power<5>(values, len, order, w, profile, work);
    case 6: return add_box_power<6>(values, len, order, w, profile, work);
    case 7: return add_box_power<7>(values, len, order, w, profile, work);
    default: return add_box_power<8>(values, len, order, w, profile, work);
    }
}

/// Pixels [begin, end) of a run, of one radius, and how that radius spreads.
struct RadiusSegment {
    int begin, end;
    SmoothPieces pieces;
};

/// out = the pixels of nc channels at v, each times its piece (a, b)'s
/// amplitude for its radius (`segments` cover them). Whether any piece
/// has weight.
DEFOCUS_CLONES
bool weigh(const float* v, const std::vector<RadiusSegment>& segments, int nc, int a, int b,
           double* out)
{
    bool weighed = false;
    for (const RadiusSegment& segment : segments) {
        const double piece_scale = segment.pieces.scale[a][b];
        weighed |= piece_scale != 0.0;
        for (size_t k = size_t(segment.begin) * nc; k < size_t(segment.end) * nc; ++k)
            out[k] = double(v[k]) * piece_scale;
    }
    return weighed;
}

/// out[i] = profile[i] * scale rounded to the nearest integer.
DEFOCUS_CLONES
void to_profile_fixed(const double* profile, size_t n, double scale, uint64_t* out)
{
    for (size_t i = 0; i < n; ++i)
        out[i] = uint64_t(int64_t(std::nearbyint(profile[i] * scale)));
}

/// row[i] += coef * profile[i], wrapping around as the column sums do.
DEFOCUS_CLONES
void add_profile(uint64_t* row, const uint64_t* profile, uint64_t coef, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        row[i] += coef * profile[i];
}

/// One row of the column integration: `sums` (order rows of n) take the
/// next delta row `deltas`, and `out` gets the last sum over `scale`, plus
/// `exact` where given.
DEFOCUS_CLONES
void integrate_down(uint64_t* sums, const uint64_t* deltas, int order, size_t n, double scale,
                    const double* exact, float* out)
{
    for (size_t k = 0; k < n; ++k)
        sums[k] += deltas[k];
    for (int pass = 1; pass < order; ++pass)
        for (size_t k = 0; k < n; ++k)
            sums[pass * n + k] += sums[(pass - 1) * n + k];
    const uint64_t* last = sums + (order - 1) * n;
    const double inverse = 1.0 / scale;
    if (exact)
        for (size_t k = 0; k < n; ++k)
            out[k] = float(double(int64_t(last[k])) * inverse + exact[k]);
    else
        for (size_t k = 0; k < n; ++k)
            out[k] = float(double(int64_t(last[k])) * inverse);
}

/// A run of pixels is filtered along x when its row profile reaches at
/// most this many times its length beyond each end (see spread_smooth).
constexpr int profile_stretch = 64;

/// Scratch of one thread for a run's row profiles.
struct RunScratch {
    std::vector<RadiusSegment> segments;
    std::vector<double> amplitudes, work, profile;
    std::vector<uint64_t> fixed;
};

/// The rows [r0, r1) of the accumulation that one thread owns: the
/// profiles' delta rows and the corners, each made at its first use.
struct Band {
    int r0, r1;
    size_t row_len;
    std::unique_ptr<uint64_t[]> profiles;
    std::unique_ptr<Fixed[]> corners;

    template<typename T>
    T* rows(std::unique_ptr<T[]>& made)
    {
        if (!made) {
            const size_t n = size_t(r1 - r0) * row_len;
            made = fresh_array<T>(n, 1);
            std::fill(&made[0], &made[n], T(0));
        }
        return made.get();
    }
};

/// The accumulation of spread_smooth over rows of `ext`, `nc` channels a
/// pixel. Runs of pixels add their row profiles' delta rows in 64-bit
/// fixed point; pixels in short runs add their corner deltas in 128-bit
/// fixed point, integrated along x before the columns. Each band of rows
/// makes either only if it has such pixels.
struct SmoothAccumulator {
    ROI ext;
    int nc, order;
    size_t row_len;
    double scale;  ///< of the 64-bit fixed point
    std::vector<const uint64_t*> profile_rows;  ///< by row; null where its band has none
    std::vector<const Fixed*> corner_rows;      ///< by row; null where its band has none
    std::mutex kept_mutex;
    std::vector<Band> kept;
    int binomials[4];  ///< of `order` (at most 3), by k: made once, they divide

    SmoothAccumulator(const ROI& ext, int nc, int order, double scale)
        : ext(ext), nc(nc), order(order), row_len(size_t(ext.width()) * nc), scale(scale)
        , profile_rows(size_t(ext.height()), nullptr)
        , corner_rows(size_t(ext.height()), nullptr)
    {
        for (int k = 0; k <= order; ++k)
            binomials[k] = binomial(order, k);
    }

    /// The signed binomial of delta k: (-1)^k C(order, k).
    int delta_coefficient(int k) const { return (k % 2 ? -1 : 1) * binomials[k]; }

    /// Pixel (x, y)'s value `v` as the corner deltas of its four separable
    /// pieces (widths `ws`) in `band`. Deltas beyond the right edge only
    /// reach further out: dropped.
    void scatter_corners(int x, int y, const float* v, const SmoothPieces& pieces,
                         Band& band) const
    {
        const Widths& ws = pieces.ws;
        for (int a = 0; a < 2; ++a)
            for (int b = 0; b < 2; ++b) {
                const double piece_scale = pieces.scale[a][b];
                if (piece_scale == 0.0)
                    continue;
                Fixed amplitude[8];
                for (int c = 0; c < nc; ++c)
                    amplitude[c] = to_fixed(double(v[c]) * piece_scale * fixed_scale);
                for (int k = 0; k <= order; ++k) {
                    const int row = y - ext.ybegin - half_support(order, ws.w[b]) + k * ws.w[b];
                    if (row < band.r0 || row >= band.r1)
                        continue;
                    Fixed* band_row = band.rows(band.corners) + size_t(row - band.r0) * row_len;
                    for (int l = 0; l <= order; ++l) {
                        const int col = x - ext.xbegin - half_support(order, ws.w[a]) + l * ws.w[a];
                        if (col >= ext.width())
                            continue;
                        const __int128 coef = __int128(delta_coefficient(k)) * delta_coefficient(l);
                        Fixed* p = band_row + size_t(col) * nc;
                        for (int c = 0; c < nc; ++c)
                            p[c] += amplitude[c] * Fixed(coef);
                    }
                }
            }
    }

    /// Pixels [x0, x1) of source row y, all of the pair of widths `ws`: for each
    /// vertical piece b, the row profile of both horizontal pieces (each
    /// pixel's amplitude filtered by its box power), rounded once to fixed
    /// point and added to the piece's delta rows that lie in `band`.
    void add_run(int x0, int x1, int y, const SpreadInputs& in, const Widths& ws, Band& band,
                 RunScratch& s) const
    {
        const int len = x1 - x0;
        const float* radii = in.radii(x0, y);
        s.segments.clear();
        for (int i = 0; i < len;) {
            int end = i + 1;
            while (end < len && radii[end] == radii[i])
                ++end;
            s.segments.push_back({ i, end, SmoothPieces(order, radii[i]) });
            i = end;
        }
        const int widest = half_support(order, ws.w[1]);
        const size_t values = size_t(len + 2 * widest) * nc;
        const size_t first = size_t(x0 - ext.xbegin - widest) * nc;
        for (int b = 0; b < 2; ++b) {
            const int row0 = y - ext.ybegin - half_support(order, ws.w[b]);
            const int first_k = band.r0 > row0 ? (band.r0 - row0 + ws.w[b] - 1) / ws.w[b] : 0;
            if (first_k > order || row0 + first_k * ws.w[b] >= band.r1)
                continue;
            s.profile.assign(values, 0.0);
            s.amplitudes.resize(size_t(len) * nc);
            bool lit = false;
            for (int a = 0; a < 2; ++a) {
                if (!weigh(in.pixels(x0, y), s.segments, nc, a, b, s.amplitudes.data()))
                    continue;
                lit = true;
                add_box_power(s.amplitudes.data(), len, nc, order, ws.w[a],
                              s.profile.data() + size_t(widest - half_support(order, ws.w[a])) * nc,
                              s.work);
            }
            if (!lit)
                continue;
            s.fixed.resize(values);
            to_profile_fixed(s.profile.data(), values, scale, s.fixed.data());
            uint64_t* rows = band.rows(band.profiles);
            for (int k = first_k; k <= order && row0 + k * ws.w[b] < band.r1; ++k)
                add_profile(rows + size_t(row0 + k * ws.w[b] - band.r0) * row_len + first,
                            s.fixed.data(), uint64_t(int64_t(delta_coefficient(k))), values);
        }
    }

    /// Keeps `band` for the column integration, its corners integrated
    /// `order` times along x first.
    void keep(Band&& band)
    {
        for (int row = band.r0; row < band.r1; ++row) {
            const size_t at = size_t(row - band.r0) * row_len;
            if (band.profiles)
                profile_rows[row] = &band.profiles[at];
            if (!band.corners)
                continue;
            Fixed* p = &band.corners[at];
            for (int pass = 0; pass < order; ++pass)
                for (size_t k = nc; k < row_len; ++k)
                    p[k] += p[k - nc];
            corner_rows[row] = p;
        }
        std::lock_guard<std::mutex> lock(kept_mutex);
        kept.push_back(std::move(band));
    }

    /// Each column integrated `order` times, in column chunks, into float.
    void integrate_columns(float* out, int nthreads) const
    {
        const auto first_corners = std::find_if(corner_rows.begin(), corner_rows.end(),
                                                [](const Fixed* row) { return row; });
        const int64_t corners_from = first_corners - corner_rows.begin();
        OIIO::parallel_for_chunked(0, int64_t(row_len), 0, [&](int64_t k0, int64_t k1) {
            const size_t n = size_t(k1 - k0);
            std::vector<uint64_t> sums(n * order, 0), none(n, 0);
            const bool corners = corners_from < ext.height();
            std::vector<Fixed> corner_sums(corners ? n * order : 0, Fixed(0));
            std::vector<double> exact(corners ? n : 0);
            for (int64_t y = 0; y < ext.height(); ++y) {
                if (y >= corners_from) {
                    const Fixed* a = corner_rows[y] ? corner_rows[y] + k0 : nullptr;
                    for (size_t k = 0; k < n; ++k) {
                        Fixed* s = &corner_sums[k * order];
                        if (a)
                            s[0] += a[k];
                        for (int pass = 1; pass < order; ++pass)
                            s[pass] += s[pass - 1];
                        exact[k] = double(__int128(s[order - 1])) / fixed_scale;
                    }
                }
                integrate_down(sums.data(), profile_rows[y] ? profile_rows[y] + k0 : none.data(),
                               order, n, scale, y >= corners_from ? exact.data() : nullptr,
                               out + y * row_len + k0);
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
                          nc, order, profile_scale(largest_magnitude(in, nthreads)));
    const ROI& ext = acc.ext;

    // Each band of rows takes the deltas of every source row that reaches
    // it. Deltas beyond the bottom edge only reach further out: dropped.
    for_each_row_band(0, ext.height(), nthreads, [&](int r0, int r1) {
        Band band { r0, r1, acc.row_len, nullptr, nullptr };
        // A source row writes rows from y - half to y + half + order.
        const int ylo = std::max(roi.ybegin, ext.ybegin + r0 - reach - order);
        const int yhi = std::min(roi.yend, ext.ybegin + r1 + reach);
        // Neighbours mostly share a radius: its pieces made once per change.
        float radius = NAN;
        SmoothPieces pieces(order, 0.0);
        RunScratch scratch;
        for (int y = ylo; y < yhi; ++y)
            for (int x = roi.xbegin; x < roi.xend;) {
                if (is_zero(in.pixels(x, y), nc)) {
                    ++x;
                    continue;
                }
                if (*in.radii(x, y) != radius) {
                    radius = *in.radii(x, y);
                    pieces = SmoothPieces(order, radius);
                }
                // A run of lit pixels of one pair of widths is filtered
                // along x unless its profile, which reaches the wider
                // width's half support beyond each end, would be more than
                // profile_stretch times as long. That bounds a pixel's
                // cost by a constant either way. A short run by profile
                // costs more than its corners, but a band without corners
                // skips their 128-bit buffer: on the garden's tent and
                // smooth, spread and composite took 0.6x the time of a
                // stretch of 2 (half a footprint long, as corners were
                // chosen before).
                const int w0 = pieces.ws.w[0];
                int end = x + 1;
                while (end < roi.xend && !is_zero(in.pixels(end, y), nc)
                       && (*in.radii(end, y) == radius
                           || smooth_widths(order, *in.radii(end, y)).w[0] == w0))
                    ++end;
                if (half_support(order, pieces.ws.w[1]) <= profile_stretch * (end - x)) {
                    acc.add_run(x, end, y, in, pieces.ws, band, scratch);
                    x = end;
                    continue;
                }
                for (; x < end; ++x) {
                    if (*in.radii(x, y) != radius) {
                        radius = *in.radii(x, y);
                        pieces = SmoothPieces(order, radius);
                    }
                    acc.scatter_corners(x, y, in.pixels(x, y), pieces, band);
                }
            }
        acc.keep(std::move(band));
    });

    reset_for_overwrite(dst, output_spec(src, ext), nthreads);  // every pixel is written below
    acc.integrate_columns(static_cast<float*>(dst.localpixels()), nthreads);
    return true;
}

}  // namespace defocus
