#include "spread/spread_engine.h"

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <mutex>

#include <OpenImageIO/parallel.h>

#include <defocus/spread/footprint.h>

#include "util/parallel_rows.h"
#include "util/simd.h"

namespace defocus {

using OIIO::ROI;

namespace {

constexpr int max_level = 5;               ///< blocks of up to 32 x 32 pixels
constexpr double transition = 1.0 / 16.0;  ///< relative radius range spread at two sizes

/// The radius from which blocks of s = 2^level pixels take over (shared
/// with the level below just before it). Blocks up to max_box pixels wide
/// spread a uniform block's exact footprint, which keeps the fidelity bars
/// from r = 4 s. Larger ones wait until r = 8 s: they average light over
/// more pixels, and from 16 pixels (wider than max_box on the
/// half-resolution grid too) they spread the shape from their centre,
/// moving light by up to s / 2.
constexpr double level_start(int level)
{
    return ((1 << level) <= max_box ? 4.0 : 8.0) * (1 << level);
}

constexpr bool level_starts_are_powers_of_two()
{
    for (int level = 0; level <= max_level; ++level) {
        const long start = long(level_start(level));
        if (double(start) != level_start(level) || (start & (start - 1)) != 0)
            return false;
    }
    return true;
}
// So r times 1 / level_start() is r over it, bit for bit, without a
// division (components()).
static_assert(level_starts_are_powers_of_two(), "inverse_level_starts() must stay exact");

/// 1 / level_start(level) for every level.
constexpr std::array<double, max_level + 1> inverse_level_starts()
{
    std::array<double, max_level + 1> inverse {};
    for (int level = 0; level <= max_level; ++level)
        inverse[size_t(level)] = 1.0 / level_start(level);
    return inverse;
}

/// The largest radius a bounded spread takes on the dense path: where
/// blocks of 2 pixels take over.
constexpr float dense_limit = float(level_start(1));
/// Blocks from this level on (4 pixels and up, from radius 15) are spread
/// at half resolution, as blocks half as wide in pixels twice as large,
/// with the shape at half the radius, and the result is interpolated back
/// (bilinearly). A block of 4 already spreads its pixels' light as if even
/// over the block, so the half-resolution grid loses nothing it kept, and
/// under a blur of 15 pixels or more the interpolation's softening of a
/// footprint's edge is invisible (on the garden scene within 0.003 dB),
/// while the deltas and the sums that integrate them drop fourfold.
constexpr int first_half_level = 2;
/// The output rows and columns one task accumulates: a tile of deltas
/// that stays in the second-level cache while every source row within
/// reach adds to it.
constexpr int tile_rows = 64, tile_columns = 256;
/// Every source pixel within reach of a tile is visited for it, so a box
/// reaching far, whose pixels all take this path, gets tiles a few times
/// its reach on a side: fewer visits outweigh a tile that leaves the cache.
constexpr int box_tile_reaches = 4, box_tile_limit = 2048;

inline bool is_zero(const float* v)
{
    return v[0] == 0.0f && v[1] == 0.0f && v[2] == 0.0f && v[3] == 0.0f;
}

/// a / 2^shift, rounded down (GCC shifts negative numbers arithmetically).
DEFOCUS_KERNEL int floor_shift(int a, int shift)
{
    return a >> shift;
}

int floor_div(int a, int b)  // b > 0
{
    return a >= 0 ? a / b : -((-a + b - 1) / b);
}

/// Level 0 is a single pixel; level L > 0 a block of 2^L pixels.
struct Component {
    int level;
    float weight;
};

/// The levels a pixel is spread at, and their shares. Level L > 0 takes
/// radii from level_start(L); just below that, radii are shared between
/// levels L - 1 and L, so that footprints change continuously.
int components(SpreadMethod method, float r, bool keep_exact, Component out[2])
{
    if (method != SpreadMethod::Bounded || !(r >= smallest_merged_radius()) || keep_exact) {
        out[0] = { 0, 1.0f };
        return 1;
    }
    static constexpr std::array<double, max_level + 1> inverse_start = inverse_level_starts();
    int level = 1;
    while (level < max_level && r * inverse_start[level + 1] >= 1.0 - transition)
        ++level;
    const double u = (r * inverse_start[level] - (1.0 - transition)) / transition;
    if (u <= 0.0) {  // where the transition starts: the smaller size alone
        out[0] = { level - 1, 1.0f };
        return 1;
    }
    if (u < 1.0) {
        out[0] = { level - 1, float(1.0 - u) };
        out[1] = { level, float(u) };
        return 2;
    }
    out[0] = { level, 1.0f };
    return 1;
}

/// How far footprints' deltas reach: rows and columns relative to their
/// anchor pixel.
struct Reach {
    int first_row, last_row, first_column, last_column;
};

/// Consecutive pixels or blocks (a block's width apart) that share a
/// footprint program: n of them from anchor column x, their colours from
/// index `at` of a colour array. When they all blend the program's two
/// sizes alike (one radius: a plane, a sky), the run keeps that blend `t`
/// and 4 values per item; otherwise 4 values per item on the smaller size
/// and then 4 per item on the larger one.
struct ProgramRun {
    int x, n, k, at;
    float t;
    bool blended;
};

Reach box_reach(float max_radius)
{
    const BoxEdges e = box_edges(box_half_width(max_radius));
    return { e.first, e.last + 1, e.first, e.last + 1 };
}

Reach program_reach(const FootprintProgram& p)
{
    return { p.first_row(), p.last_row(), p.first_column(), p.last_column() };
}

}  // namespace

double smallest_merged_radius()
{
    return level_start(1) * (1.0 - transition);
}

ShapePrograms::ShapePrograms(std::shared_ptr<const RowProfile> profile, double max_radius)
{
    for (int level = 0; level <= max_level; ++level)
        m_families.push_back(std::make_unique<ProgramFamily>(
            profile, 1 << level, (1 << level) / radius_bins_per_pixel, max_radius));
}

/// One row of pixels or blocks to spread, as runs.
struct ItemRow {
    std::vector<ProgramRun> runs;  ///< by first column
    std::vector<double> color;
    int longest = 0;               ///< items in the longest run

    void clear()
    {
        runs.clear();
        color.clear();
        longest = 0;
    }
    /// Appends a run of n items of program k, blending its sizes by t
    /// alike (folded) or not (blended), and returns where its colours go:
    /// 4 values per item, then for a blended run 4 more per item on the
    /// larger size.
    double* add_run(int x, int n, int k, float t, bool blended)
    {
        longest = std::max(longest, n);
        runs.push_back({ x, n, k, int(color.size()), blended ? 0.0f : t, blended });
        color.resize(color.size() + size_t(n) * (blended ? 8 : 4));
        return color.data() + runs.back().at;
    }
};

/// The pixels or blocks of one level that take the sparse path, on the
/// grid they are spread at: full resolution, or half (see
/// first_half_level), where anchors, blocks and reach count half-resolution
/// pixels.
struct SpreadEngine::Sparse {
    using Row = ItemRow;
    int level = 0;  ///< blocks of 2^level pixels
    bool half = false;
    const ProgramFamily* family = nullptr;  ///< of blocks of grid_block() grid pixels
    int first_block_row = 0;
    std::vector<Row> rows;          ///< per block row
    Reach reach { 0, -1, 0, -1 };  ///< of its programs, from the anchor, in grid pixels

    /// Grid pixels across a block, and columns between blocks: 2^grid_shift().
    int grid_block() const { return 1 << grid_shift(); }
    int grid_shift() const { return half ? level - 1 : level; }
    /// The program of a pixel of (full-resolution) CoC radius r.
    ProgramBlend pick(double r) const { return family->pick(half ? 0.5 * r : r); }
    /// The grid pixel a block row's or column's footprints are anchored on.
    int anchor(int index) const
    {
        const int b = grid_block();
        return b == 1 ? index : index * b + b / 2 - 1;
    }
};

namespace {

/// One tile: output rows [y_begin, y_end) and columns [x_begin, x_end),
/// accumulated as deltas in cells 1.. of `cells()`-wide rows. Cell 0
/// collects the deltas left of the tile when it is the first of its band
/// (`first`); later tiles take them from the row carry.
struct Tile {
    int y_begin, y_end, x_begin, x_end;
    bool first;
    int cells() const { return x_end - x_begin + 1; }
    /// The cell of column x, or -1 when the tile does not own it.
    int cell(int x) const
    {
        if (x >= x_end)
            return -1;
        if (x < x_begin)
            return first ? 0 : -1;
        return x - x_begin + 1;
    }
};

/// What a band's thread keeps between tiles (and layers): reused, so that
/// its memory is touched once rather than once per layer.
struct Workspace {
    std::vector<ItemRow> dense;        ///< the band's dense source rows, prepared
    std::vector<double> color;         ///< scratch for preparing them
    std::vector<float> blend;
    std::vector<double> rows;          ///< the tile's delta rows
    std::vector<double> column_carry;  ///< the box's deltas integrated down the columns
    std::vector<double> row_carry;     ///< per band row, the sum left of the tile
    std::vector<double> half_rows;     ///< the same at half resolution
    std::vector<double> half_row_carry;
};

/// The half-resolution pixels that pixels [begin, end) of a row or column
/// interpolate: half-resolution pixel i is centred between pixels 2 i and
/// 2 i + 1, so pixel x lies between i = floor((x - 1) / 2) and i + 1, a
/// quarter of the way from the nearer one.
struct HalfSpan {
    int begin, end;
};

HalfSpan half_span(int begin, int end)
{
    return { floor_div(begin - 1, 2), floor_div(end - 2, 2) + 2 };
}

/// The weight of half-resolution pixel floor((x - 1) / 2) + 1 at pixel x.
inline double upper_weight(int x)
{
    return (x & 1) ? 0.25 : 0.75;
}

/// Half-resolution values h0 and h1 of the rows above and below a pixel,
/// h1 of weight wy, as the pixel takes them: a half-resolution pixel holds
/// the light of four pixels.
DEFOCUS_KERNEL d4 between_rows(const double* h0, const double* h1, double wy)
{
    return splat(0.25 * (1.0 - wy)) * load4(h0) + splat(0.25 * wy) * load4(h1);
}

/// The most taps of a cluster added in one pass over a run's items. A
/// uniform block of 4 spreads each edge over 5 columns (6 when two sizes
/// blend), which reach into the next block's: added whole, every cell is
/// written once. Elsewhere clusters are at most 4 wide but for a mask's
/// rows, which go 4 taps at a time.
constexpr int max_taps = 8;
DEFOCUS_KERNEL int max_cluster_taps(int shift)
{
    return shift == 2 ? max_taps : 4;
}

/// A run's colours as a cluster's taps see them: one colour per item with
/// the taps' weights blended once (Folded), or each item's share of the
/// program's two sizes with each size's weights (Blended).
struct Folded {
    const double* color;
    d4 weight[max_taps];
    DEFOCUS_KERNEL d4 tap(int t, ptrdiff_t item) const
    {
        return weight[t] * load4(color + item * 4);
    }
};

struct Blended {
    const double* smaller;  ///< colours times (1 - t)
    const double* larger;   ///< colours times t
    d4 weight[max_taps][2];
    DEFOCUS_KERNEL d4 tap(int t, ptrdiff_t item) const
    {
        return weight[t][0] * load4(smaller + item * 4) + weight[t][1] * load4(larger + item * 4);
    }
};

/// What the taps of one cluster (m <= 4) put on cell q of a run of items
/// one column apart, items [lo, hi), item i's first tap at cell i.
template<typename Colors>
DEFOCUS_KERNEL d4 cluster_value(const Colors& c, int m, int q, int lo, int hi)
{
    d4 sum = splat(0.0);
    for (int t = std::max(0, q - hi + 1); t <= std::min(m - 1, q - lo); ++t)
        sum += c.tap(t, q - t);
    return sum;
}

/// cells[i] += the taps' sum over items q - M + 1 .. q, q = q0 + i, for
/// i < n, all of them items of the run.
template<int M, typename Colors>
DEFOCUS_KERNEL void cluster_body(double* cells, const Colors& c, int q0, int n)
{
    for (int i = 0; i < n; ++i) {
        d4 sum = load4(cells + size_t(i) * 4);
        for (int t = 0; t < M; ++t)
            sum += c.tap(t, ptrdiff_t(q0 + i) - t);
        store4(cells + size_t(i) * 4, sum);
    }
}

/// Adds the M taps of items [lo, hi), `stride` columns apart, item lo's
/// first tap at `cells`.
template<int M, typename Colors>
DEFOCUS_KERNEL void items_body(double* cells, const Colors& c, int stride, int lo, int hi)
{
    for (int i = lo; i < hi; ++i, cells += size_t(stride) * 4) {
        d4 tap[M];  // read before any cell is written, so the colour is loaded once
        for (int t = 0; t < M; ++t)
            tap[t] = c.tap(t, i);
        for (int t = 0; t < M; ++t)
            store4(cells + t * 4, load4(cells + t * 4) + tap[t]);
    }
}

/// Adds the M taps of items [lo, hi) S columns apart (S < M <= 2 S), item
/// lo's first tap at `cells`. Neighbours' taps share cells; each cell is
/// written once, with the earlier item's last M - S taps carried in
/// registers, so that no item waits for the store of the one before and
/// no cell is visited twice.
template<int S, int M, typename Colors>
DEFOCUS_KERNEL void carried_items_body(double* cells, const Colors& c, int lo, int hi)
{
    static_assert(S < M && M <= 2 * S, "the taps of an item reach into the next one's only");
    constexpr int carried = M - S;
    d4 carry[carried];
    for (int u = 0; u < carried; ++u)
        carry[u] = splat(0.0);
    for (int i = lo; i < hi; ++i, cells += S * 4) {
        d4 tap[M];  // read before any cell is written, so the colour is loaded once
        for (int t = 0; t < M; ++t)
            tap[t] = c.tap(t, i);
        for (int u = 0; u < S; ++u) {
            d4 sum = load4(cells + u * 4) + tap[u];
            if (u < carried)
                sum += carry[u];
            store4(cells + u * 4, sum);
        }
        for (int u = 0; u < carried; ++u)
            carry[u] = tap[S + u];
    }
    for (int u = 0; u < carried; ++u)
        store4(cells + u * 4, load4(cells + u * 4) + carry[u]);
}

/// Adds one cluster of m <= max_cluster_taps(shift) taps for items
/// [lo, hi) of a run whose items are 2^shift columns apart, item 0's first
/// tap at cell cb. Along a run of pixels one column apart, which share
/// cells, each cell is written once; blocks further apart are written item
/// by item.
template<typename Colors>
DEFOCUS_KERNEL void add_cluster(double* row, const Colors& c, int m, int cb, int shift, int lo,
                                int hi, const Tile& tile)
{
    const int last_cell = tile.cells() - 1;
    if (shift > 0) {
        // Items whose taps all lie left of the tile, those that touch it
        // at its edges (tap by tap), and those wholly inside.
        const int stride = 1 << shift;
        const int touch_lo = std::max(lo, -floor_shift(cb + m - 2, shift));
        const int touch_hi = std::min(hi, floor_shift(last_cell - cb, shift) + 1);
        const int inside_lo = std::max(touch_lo, -floor_shift(cb - 1, shift));
        const int inside_hi =
            std::max(inside_lo, std::min(touch_hi, floor_shift(last_cell - m + 1 - cb, shift) + 1));
        if (tile.first && lo < touch_lo) {
            d4 sum = splat(0.0);
            for (int i = lo; i < std::min(hi, touch_lo); ++i)
                for (int t = 0; t < m; ++t)
                    sum += c.tap(t, i);
            store4(row, load4(row) + sum);
        }
        auto add_item = [&](int i) {
            for (int t = 0; t < m; ++t) {
                const int cell = tile.cell(tile.x_begin - 1 + cb + stride * i + t);
                if (cell >= 0)
                    store4(row + size_t(cell) * 4, load4(row + size_t(cell) * 4) + c.tap(t, i));
            }
        };
        for (int i = touch_lo; i < std::min(touch_hi, inside_lo); ++i)
            add_item(i);
        if (inside_lo < inside_hi) {
            double* cells = row + size_t(cb + stride * inside_lo) * 4;
            switch (m) {
            case 1: items_body<1>(cells, c, stride, inside_lo, inside_hi); break;
            case 2: items_body<2>(cells, c, stride, inside_lo, inside_hi); break;
            case 3:
                if (shift == 1)
                    carried_items_body<2, 3>(cells, c, inside_lo, inside_hi);
                else
                    items_body<3>(cells, c, stride, inside_lo, inside_hi);
                break;
            case 4:
                if (shift == 1)
                    carried_items_body<2, 4>(cells, c, inside_lo, inside_hi);
                else
                    items_body<4>(cells, c, stride, inside_lo, inside_hi);
                break;
            // Wider clusters come at blocks 4 columns apart only.
            case 5: carried_items_body<4, 5>(cells, c, inside_lo, inside_hi); break;
            case 6: carried_items_body<4, 6>(cells, c, inside_lo, inside_hi); break;
            case 7: carried_items_body<4, 7>(cells, c, inside_lo, inside_hi); break;
            default: carried_items_body<4, 8>(cells, c, inside_lo, inside_hi); break;
            }
        }
        for (int i = inside_hi; i < touch_hi; ++i)
            add_item(i);
        return;
    }
    // Cells q of the run: cell cb + q for q in [lo, hi + m - 2].
    const int q_last = hi + m - 2;
    if (tile.first && lo < 1 - cb) {  // left of the tile: into cell 0
        d4 sum = splat(0.0);
        for (int q = lo; q <= std::min(q_last, -cb); ++q)
            sum += cluster_value(c, m, q, lo, hi);
        store4(row, load4(row) + sum);
    }
    const int in_lo = std::max(lo, 1 - cb), in_hi = std::min(q_last, last_cell - cb);
    // Cells with all of their taps on items of the run, and the ends.
    const int body_lo = std::max(in_lo, lo + m - 1), body_hi = std::min(in_hi, hi - 1);
    const int head_hi = std::min(in_hi, body_lo - 1);
    const int tail_lo = std::max(body_lo, body_hi + 1);
    auto add_value = [&](int q) {
        double* px = row + size_t(cb + q) * 4;
        store4(px, load4(px) + cluster_value(c, m, q, lo, hi));
    };
    for (int q = in_lo; q <= head_hi; ++q)
        add_value(q);
    if (body_lo <= body_hi) {
        double* cells = row + size_t(cb + body_lo) * 4;
        const int n = body_hi - body_lo + 1;
        switch (m) {
        case 1: cluster_body<1>(cells, c, body_lo, n); break;
        case 2: cluster_body<2>(cells, c, body_lo, n); break;
        case 3: cluster_body<3>(cells, c, body_lo, n); break;
        default: cluster_body<4>(cells, c, body_lo, n); break;
        }
    }
    for (int q = tail_lo; q <= in_hi; ++q)
        add_value(q);
}

/// Adds row `o` of a run's program for its items [lo, hi), which are
/// 2^shift columns apart, item 0 at cell c0 (before the program's own
/// columns).
DEFOCUS_KERNEL void add_run(double* row, const FootprintProgram& p, int o, const ProgramRun& run,
                            const double* color, int c0, int shift, int lo, int hi,
                            const Tile& tile)
{
    const double* w0 = p.smaller();
    const double* w1 = p.larger();
    // Wider clusters (a mask's rows) go a few taps at a time.
    const int most = max_cluster_taps(shift);
    for (const DeltaCluster* c = p.begin(o); c != p.end(o); ++c)
        for (int first = 0; first < c->taps; first += most) {
            const int m = std::min(most, c->taps - first);
            const int at = c->at + first;
            if (run.blended) {
                Blended b;
                b.smaller = color;
                b.larger = color + size_t(run.n) * 4;
                for (int t = 0; t < m; ++t) {
                    b.weight[t][0] = splat(w0[at + t]);
                    b.weight[t][1] = splat(w1[at + t]);
                }
                add_cluster(row, b, m, c0 + c->column + first, shift, lo, hi, tile);
            } else {
                Folded f;
                f.color = color;
                for (int t = 0; t < m; ++t)
                    f.weight[t] = splat(w0[at + t] + run.t * (w1[at + t] - w0[at + t]));
                add_cluster(row, f, m, c0 + c->column + first, shift, lo, hi, tile);
            }
        }
}

/// Appends a run of n pixels of program k, colours `color` (4 each),
/// blending its sizes by `t` each: folded when they all blend alike.
void add_run_colors(ItemRow& row, int x, int n, int k, const double* color, const float* t)
{
    const bool blended = !std::all_of(t, t + n, [&](float ti) { return ti == t[0]; });
    double* out = row.add_run(x, n, k, t[0], blended);
    if (!blended) {
        std::copy(color, color + size_t(n) * 4, out);
        return;
    }
    double* larger = out + size_t(n) * 4;
    for (int i = 0; i < n; ++i)
        for (int ch = 0; ch < 4; ++ch) {
            const double v = color[size_t(i) * 4 + ch];
            larger[size_t(i) * 4 + ch] = t[i] * v;
            out[size_t(i) * 4 + ch] = v - t[i] * v;
        }
}

/// The dense pixels of source row `sy` within [x0, x1), as runs of
/// consecutive pixels on one program.
DEFOCUS_CLONES
void prepare_dense_row(const SpreadSource& src, SpreadMethod method, const ProgramFamily& family,
                       int sy, int x0, int x1, ItemRow& row, std::vector<double>& color,
                       std::vector<float>& blend)
{
    const size_t base = size_t(sy - src.roi.ybegin) * src.roi.width() - src.roi.xbegin;
    row.clear();
    color.resize(size_t(std::max(0, x1 - x0)) * 4);
    blend.resize(size_t(std::max(0, x1 - x0)));
    // Neighbours mostly share a radius: components() and pick() once per
    // change.
    float cached_radius = NAN;
    Component c[2];
    int components_count = 0;
    ProgramBlend b { 0, 0.0f };
    int run_x = 0, n = 0, k = -1;
    for (int x = x0; x <= x1; ++x) {
        const float* v = x < x1 ? src.color + (base + x) * 4 : nullptr;
        int count = 0;
        float r = 0.0f;
        if (v && !is_zero(v)) {
            r = src.radius[base + x];
            const bool keep = src.keep_exact && src.keep_exact[base + x];
            if (keep || r != cached_radius) {
                cached_radius = keep ? NAN : r;
                components_count = components(method, r, keep, c);
                if (c[0].level == 0 && r <= dense_limit)
                    b = family.pick(r);
            }
            count = components_count;
        }
        const bool dense = count > 0 && c[0].level == 0 && r <= dense_limit;
        if (n > 0 && (!dense || b.k != k || run_x + n != x)) {
            add_run_colors(row, run_x, n, k, color.data(), blend.data());
            n = 0;
        }
        if (!dense)
            continue;
        if (n == 0) {
            run_x = x;
            k = b.k;
        }
        store4(&color[size_t(n) * 4], load4(v) * splat(count == 2 ? c[0].weight : 1.0));
        blend[n++] = b.t;
    }
}

/// The box's 16 corner deltas (Kosloff, Tao & Barsky 2009, sec. 3, with
/// fractional edges), to be integrated down the columns and then along
/// the rows. Deltas above the tile go straight into the column carry.
DEFOCUS_CLONES
void scatter_box_row(const SpreadSource& src, int sy, int x0, int x1, double* rows,
                     double* column_carry, const Tile& tile)
{
    const size_t base = size_t(sy - src.roi.ybegin) * src.roi.width() - src.roi.xbegin;
    const size_t row_size = size_t(tile.cells()) * 4;
    for (int x = x0; x < x1; ++x) {
        const float* v = src.color + (base + x) * 4;
        if (is_zero(v))
            continue;
        const double h = box_half_width(src.radius[base + x]);
        const BoxEdges e = box_edges(h);
        const int at[4] = { e.first, e.first + 1, e.last, e.last + 1 };
        const double step[4] = { e.first_cover, 1.0 - e.first_cover, e.last_cover - 1.0,
                                 -e.last_cover };
        const d4 value = load4(v) * splat(1.0 / (4.0 * h * h));
        int cell[4];
        for (int i = 0; i < 4; ++i)
            cell[i] = tile.cell(x + at[i]);
        for (int j = 0; j < 4; ++j) {
            const int y = sy + at[j];
            if (y >= tile.y_end)
                continue;
            double* row = y < tile.y_begin ? column_carry : rows + (y - tile.y_begin) * row_size;
            const d4 vy = value * splat(step[j]);
            for (int i = 0; i < 4; ++i)
                if (cell[i] >= 0) {
                    double* p = row + size_t(cell[i]) * 4;
                    store4(p, load4(p) + vy * splat(step[i]));
                }
        }
    }
}

/// The runs of a row of items (2^shift columns apart, their footprints
/// reaching `reach`) that can touch the tile's columns: [first, last).
struct RunsInReach {
    std::vector<ProgramRun>::const_iterator first, last;
    int x_lo, x_hi;  ///< the anchors whose footprints touch the columns
    bool empty() const { return first == last; }
};

RunsInReach runs_in_reach(const ItemRow& items, int shift, const Reach& reach, const Tile& tile)
{
    RunsInReach r;
    r.x_lo = tile.x_begin - reach.last_column;
    r.x_hi = tile.x_end - reach.first_column;
    r.first = std::lower_bound(items.runs.begin(), items.runs.end(),
                               r.x_lo - (items.longest - 1) * (1 << shift),
                               [](const ProgramRun& run, int x) { return run.x < x; });
    r.last = std::lower_bound(r.first, items.runs.end(), r.x_hi,
                              [](const ProgramRun& run, int x) { return run.x < x; });
    return r;
}

/// Adds the footprints of one row of items (pixels or blocks 2^shift
/// columns apart, anchored on row `anchor`) to the tile's delta rows: the
/// items' reach is `reach` (of the largest of `family`'s programs they
/// use).
DEFOCUS_CLONES
void scatter_items(const ProgramFamily& family, int shift, const Reach& reach,
                   const ItemRow& items, int anchor, double* rows, const Tile& tile)
{
    const size_t row_size = size_t(tile.cells()) * 4;
    const RunsInReach runs = runs_in_reach(items, shift, reach, tile);
    const int x_lo = runs.x_lo, x_hi = runs.x_hi;
    for (auto it = runs.first; it != runs.last; ++it) {
        const ProgramRun& run = *it;
        const int i0 = std::max(0, -floor_shift(run.x - x_lo, shift));
        const int i1 = std::min(run.n, -floor_shift(run.x - x_hi, shift));
        if (i0 >= i1)
            continue;
        const FootprintProgram& p = family.program(run.k);
        const int o_lo = std::max(p.first_row(), tile.y_begin - anchor);
        const int o_hi = std::min(p.last_row(), tile.y_end - 1 - anchor);
        const double* color = &items.color[run.at];
        const int c0 = run.x - tile.x_begin + 1;
        for (int o = o_lo; o <= o_hi; ++o)
            add_run(rows + (anchor + o - tile.y_begin) * row_size, p, o, run, color, c0, shift, i0,
                    i1, tile);
    }
}

/// Integrates a tile row along x in place (after adding it to the column
/// carry, for the box), starting from the row carry, which it updates.
DEFOCUS_CLONES
void finish_row(double* row, double* column_carry, double* row_carry, int cells)
{
    d4 sum = load4(row_carry);
    if (column_carry) {
        for (int i = 0; i < cells; ++i) {
            const d4 down = load4(column_carry + size_t(i) * 4) + load4(row + size_t(i) * 4);
            store4(column_carry + size_t(i) * 4, down);
            sum += down;
            store4(row + size_t(i) * 4, sum);
        }
    } else {
        for (int i = 0; i < cells; ++i) {
            sum += load4(row + size_t(i) * 4);
            store4(row + size_t(i) * 4, sum);
        }
    }
    store4(row_carry, sum);
}

/// Adds to cells [x_begin, x_end) of a row (`row` at x_begin) the
/// integrated half-resolution rows h0 and h1 below it, bilinearly
/// interpolated: h1 of weight wy, their cells from half-resolution column
/// `first` on. With `constant`, the row is that value, unset before.
DEFOCUS_CLONES
void add_interpolated(double* row, const double* h0, const double* h1, double wy, int x_begin,
                      int x_end, int first, const double* constant)
{
    const d4 base = constant ? load4(constant) : splat(0.0);
    auto column = [&](int i) {
        const size_t c = size_t(i - first) * 4;
        return between_rows(h0 + c, h1 + c, wy);
    };
    int i = floor_div(x_begin - 1, 2);
    d4 left = column(i), right = column(i + 1);
    for (int x = x_begin; x < x_end; ++x, row += 4) {
        if (floor_div(x - 1, 2) != i) {
            ++i;
            left = right;
            right = column(i + 1);
        }
        const double wx = upper_weight(x);
        store4(row, (constant ? base : load4(row)) + left * splat(1.0 - wx) + right * splat(wx));
    }
}

/// The pixels of one block row of one sparse level, summed per block and
/// program as they come, pixel row by pixel row; then made into runs.
class BlockRowSums {
public:
    /// Starts a block row of `blocks` blocks from block first_block.
    void start(int first_block, int blocks)
    {
        m_first = first_block;
        m_sums.assign(size_t(blocks), Sum {});
        m_others.clear();
    }

    /// Adds `value` to block `b` on program k, blending its sizes by t.
    DEFOCUS_KERNEL void add(int b, int k, float t, const d4& value)
    {
        Sum* sum = &m_sums[size_t(b - m_first)];
        // A block across a change of program keeps a sum per program,
        // chained from its first: rows where every block changes program
        // (the radius changing down the rows) find them in a step or two.
        while (sum->k >= 0 && sum->k != k) {
            if (sum->next < 0) {
                sum->next = int(m_others.size());
                m_others.emplace_back();
                sum = &m_others.back();
                break;
            }
            sum = &m_others[size_t(sum->next)];
        }
        if (sum->k < 0) {
            sum->b = b;
            sum->k = k;
            sum->t = t;
        }
        sum->blended |= sum->t != t;
        store4(sum->smaller, load4(sum->smaller) + value * splat(1.0 - t));
        store4(sum->larger, load4(sum->larger) + value * splat(t));
    }

    /// The row's blocks as runs of consecutive blocks on one program,
    /// folded when all of their pixels blend its sizes alike.
    ItemRow runs(const SpreadEngine::Sparse& level)
    {
        // Every block's first program, in block order; the few other
        // programs of blocks across a change of program, ordered by
        // program, after them; then all the runs by column.
        std::sort(m_others.begin(), m_others.end(), [](const Sum& a, const Sum& e) {
            return a.k != e.k ? a.k < e.k : a.b < e.b;
        });
        // Room for the lit blocks' sums when their runs are folded (4
        // values a block), as most are; blended ones grow it. The rows
        // live as long as the engine, so room for the most they can take
        // (8 values for every block of the row) was mostly held unused.
        const auto lit = [](const Sum& e) { return e.k >= 0; };
        ItemRow row;
        row.color.reserve(4 * size_t(std::count_if(m_sums.begin(), m_sums.end(), lit)
                                     + std::count_if(m_others.begin(), m_others.end(), lit)));
        add_runs(m_sums, level, row);
        if (m_others.empty())
            return row;
        add_runs(m_others, level, row);
        std::sort(row.runs.begin(), row.runs.end(),
                  [](const ProgramRun& a, const ProgramRun& b) { return a.x < b.x; });
        return row;
    }

private:
    struct Sum {
        int b = 0, k = -1;     ///< block and program; k < 0: no pixel yet
        int next = -1;         ///< the block's next sum in m_others, if any
        float t = 0.0f;        ///< the blend of its pixels, when they all share one
        bool blended = false;  ///< when they do not
        double smaller[4] = { 0, 0, 0, 0 }, larger[4] = { 0, 0, 0, 0 };
    };
    /// Appends `sums` (ordered so that a run's blocks are neighbours) as
    /// runs of consecutive blocks on one program, folded when all of their
    /// pixels blend its sizes alike.
    static void add_runs(const std::vector<Sum>& all, const SpreadEngine::Sparse& level,
                         ItemRow& row)
    {
        for (size_t i = 0; i < all.size();) {
            if (all[i].k < 0) {
                ++i;
                continue;
            }
            size_t j = i + 1;
            while (j < all.size() && all[j].k == all[i].k && all[j].b == all[j - 1].b + 1)
                ++j;
            const bool folded = std::all_of(all.begin() + i, all.begin() + j, [&](const Sum& e) {
                return !e.blended && e.t == all[i].t;
            });
            const int count = int(j - i);
            double* out = row.add_run(level.anchor(all[i].b), count, all[i].k, all[i].t, !folded);
            for (size_t e = i; e < j; ++e, out += 4)
                for (int ch = 0; ch < 4; ++ch) {
                    out[ch] = folded ? all[e].smaller[ch] + all[e].larger[ch] : all[e].smaller[ch];
                    if (!folded)
                        out[size_t(count) * 4 + ch] = all[e].larger[ch];
                }
            i = j;
        }
    }

    int m_first = 0;
    std::vector<Sum> m_sums;    ///< per block, its first program
    std::vector<Sum> m_others;  ///< other programs of a block
};

/// What one pass over a layer finds: the largest radius on the dense path
/// and on each sparse level, and the sparse levels' block rows, summed.
struct LayerSurvey {
    float dense_max = -1.0f;
    std::vector<uint8_t> dense_rows;  ///< per source row: any pixel on the dense path
    std::vector<float> sparse_max;
    std::vector<std::vector<ItemRow>> block_rows;  ///< per level, per block row
};

/// Surveys source rows [y0, y1), which hold whole block rows of every
/// level: each pixel's components once, dense ones noted, sparse ones
/// summed into their level's blocks.
DEFOCUS_CLONES
void survey_rows(const SpreadSource& source, SpreadMethod method,
                 const std::vector<std::unique_ptr<SpreadEngine::Sparse>>& levels, int y0, int y1,
                 LayerSurvey& found, std::mutex& merge)
{
    const ROI& roi = source.roi;
    const int nlevels = int(levels.size());
    float dense = -1.0f;
    std::vector<float> sparse(nlevels, -1.0f);
    thread_local std::vector<BlockRowSums> sums;  // reused: their rows are long
    sums.resize(nlevels);
    std::vector<int> open(nlevels, INT_MIN);  // the block row each level's sums hold
    auto finish = [&](int l) {
        if (open[l] == INT_MIN)
            return;
        const SpreadEngine::Sparse& level = *levels[l];
        found.block_rows[l][open[l] - level.first_block_row] = sums[l].runs(level);
        open[l] = INT_MIN;
    };
    // Neighbours mostly share a radius: components() and pick() once per
    // change.
    float cached_radius = NAN;
    Component c[2];
    ProgramBlend blend[2];
    int n = 0;
    for (int y = y0; y < y1; ++y) {
        const size_t row = size_t(y - roi.ybegin) * roi.width();
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t p = row + (x - roi.xbegin);
            const float* v = source.color + p * 4;
            if (is_zero(v))
                continue;
            const float r = source.radius[p];
            const bool keep = source.keep_exact && source.keep_exact[p];
            if (keep || r != cached_radius) {
                cached_radius = keep ? NAN : r;
                n = components(method, r, keep, c);
                for (int i = 0; i < n; ++i)
                    if (method != SpreadMethod::Box)
                        blend[i] = levels[c[i].level]->pick(r);
            }
            // Along a row a block's pixels mostly go alike (one radius,
            // none kept exact): those after this one in its block (the
            // smaller one of two sizes) are summed here, in registers, and
            // go to the blocks once.
            d4 value = load4(v);
            if (c[0].level > 0) {
                const int block_end =
                    std::min(roi.xend, (floor_shift(x, c[0].level) + 1) * (1 << c[0].level));
                for (size_t q = p + 1; x + 1 < block_end; ++q, ++x) {
                    const float* u = source.color + q * 4;
                    if (is_zero(u) || source.radius[q] != r
                        || (source.keep_exact && source.keep_exact[q]))
                        break;
                    value += load4(u);
                }
            }
            for (int i = 0; i < n; ++i) {
                const int l = c[i].level;
                if (method == SpreadMethod::Box || (l == 0 && r <= dense_limit)) {
                    dense = std::max(dense, r);
                    found.dense_rows[size_t(y - roi.ybegin)] = 1;
                    continue;
                }
                sparse[l] = std::max(sparse[l], r);
                const int by = floor_shift(y, l);
                if (open[l] != by) {
                    finish(l);
                    open[l] = by;
                    const int first = floor_shift(roi.xbegin, l);
                    sums[l].start(first, floor_shift(roi.xend - 1, l) - first + 1);
                }
                sums[l].add(floor_shift(x, l), blend[i].k, blend[i].t,
                            value * splat(c[i].weight));
            }
        }
    }
    for (int l = 0; l < nlevels; ++l)
        finish(l);
    std::lock_guard<std::mutex> lock(merge);
    found.dense_max = std::max(found.dense_max, dense);
    for (int l = 0; l < nlevels; ++l)
        found.sparse_max[l] = std::max(found.sparse_max[l], sparse[l]);
}

}  // namespace

SpreadEngine::SpreadEngine(const SpreadSource& source, SpreadMethod method,
                           const ShapePrograms* shape, int nthreads)
    : m_source(source)
    , m_method(method)
    , m_shape(shape)
{
    const ROI& roi = source.roi;
    // Every level a pixel might take, and the block rows it would fill.
    std::vector<std::unique_ptr<Sparse>> levels;
    LayerSurvey found;
    for (int l = 0; method != SpreadMethod::Box && l <= max_level; ++l) {
        auto level = std::make_unique<Sparse>();
        level->level = l;
        level->half = l >= first_half_level;
        level->family = l == 0 ? &shape->pixels() : &shape->blocks(level->grid_shift());
        level->first_block_row = floor_shift(roi.ybegin, l);
        found.block_rows.emplace_back(floor_shift(roi.yend - 1, l) - level->first_block_row + 1);
        levels.push_back(std::move(level));
    }
    found.sparse_max.assign(levels.size(), -1.0f);
    found.dense_rows.assign(size_t(roi.height()), 0);
    // One pass, in stripes of whole block rows of every level.
    const int stripe = 1 << max_level;
    const int first_stripe = floor_shift(roi.ybegin, max_level);
    const int stripes = floor_shift(roi.yend - 1, max_level) - first_stripe + 1;
    std::mutex merge;
    parallel_for_each_item(0, stripes, [&](int64_t i) {
        const int y0 = std::max(roi.ybegin, (first_stripe + int(i)) * stripe);
        const int y1 = std::min(roi.yend, (first_stripe + int(i) + 1) * stripe);
        survey_rows(source, method, levels, y0, y1, found, merge);
    }, nthreads);
    m_dense.max_radius = found.dense_max;
    m_dense.rows = std::move(found.dense_rows);

    // The last column of a footprint's deltas (and for the box the last
    // row) only ends it: the pixels it lights stop one before. Interpolated
    // from half resolution, half-resolution pixel i lights pixels 2 i - 1
    // to 2 i + 2.
    auto grow = [&](const ROI& anchors, const Reach& reach, bool box, bool half) {
        ROI lit(anchors.xbegin + reach.first_column, anchors.xend + reach.last_column - 1,
                anchors.ybegin + reach.first_row, anchors.yend + reach.last_row - box, 0, 1, 0, 4);
        if (half)
            lit = ROI(2 * lit.xbegin - 1, 2 * lit.xend + 1, 2 * lit.ybegin - 1, 2 * lit.yend + 1,
                      0, 1, 0, 4);
        m_extent = m_extent.defined() ? OIIO::roi_union(m_extent, lit) : lit;
    };
    if (m_dense.max_radius >= 0.0f) {
        const Reach reach = method == SpreadMethod::Box
                                ? box_reach(m_dense.max_radius)
                                : program_reach(shape->pixels().program(
                                    shape->pixels().pick(m_dense.max_radius).k));
        m_dense.first_row = reach.first_row;
        m_dense.last_row = reach.last_row;
        m_dense.first_column = reach.first_column;
        m_dense.last_column = reach.last_column;
        grow(roi, reach, method == SpreadMethod::Box, false);
    }

    for (size_t l = 0; l < levels.size(); ++l) {
        if (found.sparse_max[l] < 0.0f)
            continue;
        std::unique_ptr<Sparse>& level = levels[l];
        level->rows = std::move(found.block_rows[l]);
        // Programs of larger radii reach at least as far.
        level->reach = program_reach(level->family->program(level->pick(found.sparse_max[l]).k));
        const int s = 1 << level->level;
        const int first = level->first_block_row, last = first + int(level->rows.size()) - 1;
        const ROI anchors(level->anchor(floor_div(roi.xbegin, s)),
                          level->anchor(floor_div(roi.xend - 1, s)) + 1, level->anchor(first),
                          level->anchor(last) + 1);
        grow(anchors, level->reach, false, level->half);
        m_sparse.push_back(std::move(level));
    }
    if (!m_extent.defined()) {  // nothing carries light: the region itself, dark
        m_extent = roi;
        m_extent.chbegin = 0;
        m_extent.chend = 4;
    }
}

SpreadEngine::~SpreadEngine() = default;

void SpreadEngine::run(const ROI& window_in, RowSink& sink, int nthreads) const
{
    const ROI window = OIIO::roi_intersection(window_in, m_extent);
    if (window.width() <= 0 || window.height() <= 0)
        return;
    const bool dense = m_dense.max_radius >= 0.0f;
    const bool box = m_method == SpreadMethod::Box;
    const bool half = std::any_of(m_sparse.begin(), m_sparse.end(),
                                  [](const std::unique_ptr<Sparse>& level) { return level->half; });
    const ROI& roi = m_source.roi;
    const Reach dense_reach { m_dense.first_row, m_dense.last_row, m_dense.first_column,
                              m_dense.last_column };
    const int box_reach = box ? m_dense.last_row - m_dense.first_row : 0;
    const int band_rows = std::clamp(box_tile_reaches * box_reach, tile_rows, box_tile_limit);
    const int tile_width = std::clamp(box_tile_reaches * box_reach, tile_columns, box_tile_limit);
    const int bands = (window.height() + band_rows - 1) / band_rows;
    parallel_for_each_item(0, bands, [&](int64_t band) {
        thread_local Workspace ws;
        const int y_begin = window.ybegin + int(band) * band_rows;
        const int y_end = std::min(window.yend, y_begin + band_rows);
        ws.row_carry.assign(size_t(y_end - y_begin) * 4, 0.0);
        const HalfSpan half_y = half_span(y_begin, y_end);
        if (half)
            ws.half_row_carry.assign(size_t(half_y.end - half_y.begin) * 4, 0.0);
        // Source rows and columns whose deltas can land in the band.
        const int sy0 = std::max(roi.ybegin, y_begin - m_dense.last_row);
        const int sy1 = std::min(roi.yend, y_end - m_dense.first_row);
        const int sx0 = std::max(roi.xbegin, window.xbegin - m_dense.last_column);
        const int sx1 = std::min(roi.xend, window.xend - m_dense.first_column);
        if (dense && !box) {
            if (ws.dense.size() < size_t(std::max(0, sy1 - sy0)))
                ws.dense.resize(sy1 - sy0);
            for (int sy = sy0; sy < sy1; ++sy) {
                if (m_dense.rows[size_t(sy - roi.ybegin)])
                    prepare_dense_row(m_source, m_method, m_shape->pixels(), sy, sx0, sx1,
                                      ws.dense[sy - sy0], ws.color, ws.blend);
                else
                    ws.dense[sy - sy0].clear();
            }
        }
        for (int x_begin = window.xbegin; x_begin < window.xend; x_begin += tile_width) {
            const Tile tile { y_begin, y_end, x_begin, std::min(window.xend, x_begin + tile_width),
                              x_begin == window.xbegin };
            const size_t row_size = size_t(tile.cells()) * 4;
            if (box) {
                // The box's deltas, integrated down the columns: scattered
                // into the whole tile first.
                ws.rows.assign(size_t(y_end - y_begin) * row_size, 0.0);
                ws.column_carry.assign(row_size, 0.0);
                const int x0 = std::max(roi.xbegin, tile.x_begin - m_dense.last_column);
                const int x1 = std::min(roi.xend, tile.x_end - m_dense.first_column);
                for (int sy = sy0; sy < sy1 && dense && x0 < x1; ++sy)
                    scatter_box_row(m_source, sy, x0, x1, ws.rows.data(), ws.column_carry.data(),
                                    tile);
                for (int y = y_begin; y < y_end; ++y) {
                    double* row = ws.rows.data() + (y - y_begin) * row_size;
                    finish_row(row, ws.column_carry.data(),
                               ws.row_carry.data() + size_t(y - y_begin) * 4, tile.cells());
                    sink.row(y, tile.x_begin, tile.x_end, row + 4);
                }
                continue;
            }
            // The half-resolution pixels the tile's pixels interpolate.
            const HalfSpan half_x = half_span(tile.x_begin, tile.x_end);
            const Tile half_tile { half_y.begin, half_y.end, half_x.begin, half_x.end, tile.first };
            const size_t half_row_size = size_t(half_tile.cells()) * 4;
            // Shapes: every source row and block row within reach adds its
            // footprints' rows to the tile (or the half-resolution one), a
            // run at a time.
            auto item_rows = [&](auto&& visit) {
                if (dense)
                    for (int sy = sy0; sy < sy1; ++sy)
                        if (!visit(m_shape->pixels(), 0, dense_reach, ws.dense[sy - sy0], sy, false))
                            return;
                for (const std::unique_ptr<Sparse>& level : m_sparse) {
                    const Tile& t = level->half ? half_tile : tile;
                    const int s = level->grid_block(), offset = s == 1 ? 0 : s / 2 - 1;
                    const int first = level->first_block_row;
                    const int lo = std::max(first, -floor_div(-(t.y_begin - level->reach.last_row - offset), s));
                    const int hi = std::min(first + int(level->rows.size()) - 1,
                                            floor_div(t.y_end - 1 - level->reach.first_row - offset, s));
                    for (int b = lo; b <= hi; ++b)
                        if (!visit(*level->family, level->grid_shift(), level->reach,
                                   level->rows[b - first], level->anchor(b), level->half))
                            return;
                }
            };
            // Which of the tile's rows any footprint reaches: full or
            // half resolution.
            bool lit[2] = { false, false };
            item_rows([&](const ProgramFamily&, int shift, const Reach& reach, const ItemRow& items,
                          int, bool at_half) {
                lit[at_half] = lit[at_half]
                               || !runs_in_reach(items, shift, reach, at_half ? half_tile : tile).empty();
                return !(lit[0] && lit[1]);
            });
            // Row y's half-resolution rows, and the weight of the lower one.
            auto half_rows_of = [&](int y) {
                return std::pair { floor_div(y - 1, 2) - half_tile.y_begin, upper_weight(y) };
            };
            if (!lit[0] && !lit[1]) {
                // Layers are sparse: a tile that no footprint reaches only
                // carries the light from its left, mostly none.
                ws.rows.resize(row_size);
                for (int y = y_begin; y < y_end; ++y) {
                    d4 carry = load4(ws.row_carry.data() + size_t(y - y_begin) * 4);
                    if (half) {
                        const auto [j, wy] = half_rows_of(y);
                        const double* h = ws.half_row_carry.data() + size_t(j) * 4;
                        carry += between_rows(h, h + 4, wy);
                    }
                    double value[4];
                    store4(value, carry);
                    if (std::all_of(value, value + 4, [](double v) { return v == 0.0; })) {
                        sink.dark(y, tile.x_begin, tile.x_end);
                        continue;
                    }
                    for (size_t i = 0; i < row_size; i += 4)
                        std::copy(value, value + 4, ws.rows.begin() + ptrdiff_t(i));
                    sink.row(y, tile.x_begin, tile.x_end, ws.rows.data() + 4);
                }
                continue;
            }
            // Full-resolution rows no footprint reaches are their carry;
            // half-resolution ones that no footprint reaches and no light
            // from the left crosses add nothing.
            if (lit[0])
                ws.rows.assign(size_t(y_end - y_begin) * row_size, 0.0);
            else
                ws.rows.resize(size_t(y_end - y_begin) * row_size);
            const bool add_half =
                half && (lit[1] || !std::all_of(ws.half_row_carry.begin(), ws.half_row_carry.end(),
                                                [](double v) { return v == 0.0; }));
            if (add_half)
                ws.half_rows.assign(size_t(half_tile.y_end - half_tile.y_begin) * half_row_size, 0.0);
            item_rows([&](const ProgramFamily& family, int shift, const Reach& reach,
                          const ItemRow& items, int anchor, bool at_half) {
                if (at_half)
                    scatter_items(family, shift, reach, items, anchor, ws.half_rows.data(), half_tile);
                else
                    scatter_items(family, shift, reach, items, anchor, ws.rows.data(), tile);
                return true;
            });
            if (add_half) {
                // The next tile's half-resolution pixels start left of this
                // one's end: its carry is the sum left of them.
                const bool last = tile.x_end == window.xend;
                const int carried = half_span(tile.x_end, tile.x_end + 1).begin - half_tile.x_begin;
                for (int j = half_tile.y_begin; j < half_tile.y_end; ++j) {
                    double* row = ws.half_rows.data() + size_t(j - half_tile.y_begin) * half_row_size;
                    double* carry = ws.half_row_carry.data() + size_t(j - half_tile.y_begin) * 4;
                    finish_row(row, nullptr, carry, half_tile.cells());
                    if (!last)
                        std::copy(row + size_t(carried) * 4, row + size_t(carried) * 4 + 4, carry);
                }
            }
            for (int y = y_begin; y < y_end; ++y) {
                double* row = ws.rows.data() + (y - y_begin) * row_size;
                double* carry = ws.row_carry.data() + size_t(y - y_begin) * 4;
                if (lit[0])
                    finish_row(row, nullptr, carry, tile.cells());
                if (add_half) {
                    const auto [j, wy] = half_rows_of(y);
                    const double* h0 = ws.half_rows.data() + size_t(j) * half_row_size;
                    add_interpolated(row + 4, h0, h0 + half_row_size, wy, tile.x_begin, tile.x_end,
                                     half_tile.x_begin - 1, lit[0] ? nullptr : carry);
                }
                sink.row(y, tile.x_begin, tile.x_end, row + 4);
            }
        }
    }, nthreads);
}

}  // namespace defocus
