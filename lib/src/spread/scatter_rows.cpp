#include "spread/scatter_rows.h"

#include <algorithm>
#include <cmath>

namespace defocus {

namespace {

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

/// add_cluster for items 2^shift > 1 columns apart: written item by item.
template<typename Colors>
DEFOCUS_KERNEL void add_spaced_cluster(double* row, const Colors& c, int m, int cb, int shift,
                                       int lo, int hi, const Tile& tile)
{
    const int last_cell = tile.cells() - 1;
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
}

/// add_cluster for items one column apart, which share cells: each cell is
/// written once.
template<typename Colors>
DEFOCUS_KERNEL void add_adjacent_cluster(double* row, const Colors& c, int m, int cb, int lo,
                                         int hi, const Tile& tile)
{
    const int last_cell = tile.cells() - 1;
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

/// Adds one cluster of m <= max_cluster_taps(shift) taps for items
/// [lo, hi) of a run whose items are 2^shift columns apart, item 0's first
/// tap at cell cb.
template<typename Colors>
DEFOCUS_KERNEL void add_cluster(double* row, const Colors& c, int m, int cb, int shift, int lo,
                                int hi, const Tile& tile)
{
    if (shift > 0)
        add_spaced_cluster(row, c, m, cb, shift, lo, hi, tile);
    else
        add_adjacent_cluster(row, c, m, cb, lo, hi, tile);
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

/// Appends a run of n pixels of program k of `family`, colours `color` (4
/// each), blending its sizes by `t` each: folded when they all blend alike.
void add_run_colors(ItemRow& row, int x, int n, int k, const ProgramFamily* family,
                    const double* color, const float* t)
{
    const bool blended = !std::all_of(t, t + n, [&](float ti) { return ti == t[0]; });
    double* out = row.add_run(x, n, k, t[0], blended, family);
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

}  // namespace

DEFOCUS_CLONES
void prepare_dense_row(const SpreadSource& src, SpreadMethod method, const ShapePrograms& shape,
                       int sy, int x0, int x1, ItemRow& row, std::vector<double>& color,
                       std::vector<float>& blend)
{
    const ProgramFamily& pixels = shape.pixels();
    FamilyFinder families(shape, 0, src.cateye_side);
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
    const ProgramFamily* family = nullptr;  // of the pixel at x
    const ProgramFamily* run_family = nullptr;
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
                    b = pixels.pick(r);
            }
            count = components_count;
        }
        const bool dense = count > 0 && c[0].level == 0 && r <= dense_limit;
        if (dense)
            family = families.at(x + 0.5, sy + 0.5, 1, r);
        if (n > 0 && (!dense || b.k != k || family != run_family || run_x + n != x)) {
            add_run_colors(row, run_x, n, k, run_family, color.data(), blend.data());
            n = 0;
        }
        if (!dense)
            continue;
        if (n == 0) {
            run_x = x;
            k = b.k;
            run_family = family;
        }
        store4(&color[size_t(n) * 4], load4(v) * splat(count == 2 ? c[0].weight : 1.0));
        blend[n++] = b.t;
    }
}

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
        const BoxHalfWidths h = box_half_widths(src.radius[base + x], src.box_aspect);
        const BoxEdges ex = box_edges(h.x), ey = box_edges(h.y);
        const int at_x[4] = { ex.first, ex.first + 1, ex.last, ex.last + 1 };
        const int at_y[4] = { ey.first, ey.first + 1, ey.last, ey.last + 1 };
        const double step_x[4] = { ex.first_cover, 1.0 - ex.first_cover, ex.last_cover - 1.0,
                                   -ex.last_cover };
        const double step_y[4] = { ey.first_cover, 1.0 - ey.first_cover, ey.last_cover - 1.0,
                                   -ey.last_cover };
        const d4 value = load4(v) * splat(1.0 / (4.0 * h.x * h.y));
        int cell[4];
        for (int i = 0; i < 4; ++i)
            cell[i] = tile.cell(x + at_x[i]);
        for (int j = 0; j < 4; ++j) {
            const int y = sy + at_y[j];
            if (y >= tile.y_end)
                continue;
            double* row = y < tile.y_begin ? column_carry : rows + (y - tile.y_begin) * row_size;
            const d4 vy = value * splat(step_y[j]);
            for (int i = 0; i < 4; ++i)
                if (cell[i] >= 0) {
                    double* p = row + size_t(cell[i]) * 4;
                    store4(p, load4(p) + vy * splat(step_x[i]));
                }
        }
    }
}

DEFOCUS_CLONES
void scatter_items(int shift, const Reach& reach, const ItemRow& items, int anchor,
                   double* rows, const Tile& tile)
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
        const FootprintProgram& p = run.family->program(run.k);
        const int o_lo = std::max(p.first_row(), tile.y_begin - anchor);
        const int o_hi = std::min(p.last_row(), tile.y_end - 1 - anchor);
        const double* color = &items.color[run.at];
        const int c0 = run.x - tile.x_begin + 1;
        for (int o = o_lo; o <= o_hi; ++o)
            add_run(rows + (anchor + o - tile.y_begin) * row_size, p, o, run, color, c0, shift, i0,
                    i1, tile);
    }
}

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

}  // namespace defocus
