#include "spread/cell_spread.h"

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <utility>

#include <immintrin.h>

#include "util/parallel_rows.h"
#include "util/simd.h"

namespace defocus {

namespace {

/// Narrower than this, a rectangle is taken this wide about its centre:
/// its density stays finite.
constexpr double narrowest = 1e-3;

/// An interval's corner deltas along one axis: after a prefix sum, pixel i
/// holds the length of [i, i + 1] the interval covers over its length.
struct AxisDeltas {
    int at[4];
    double weight[4];
};

/// The deltas of [a, b] (narrower than `narrowest`: that wide about its
/// centre), cut to [lo, hi]: the part outside adds nothing.
DEFOCUS_KERNEL AxisDeltas axis_deltas(double a, double b, double lo, double hi)
{
    if (b - a < narrowest) {
        const double centre = 0.5 * (a + b);
        a = centre - 0.5 * narrowest;
        b = centre + 0.5 * narrowest;
    }
    const double scale = 1.0 / (b - a);
    a = std::clamp(a, lo, hi);
    b = std::clamp(b, lo, hi);
    const double fa = std::floor(a), fb = std::floor(b);
    return { { int(fa), int(fa) + 1, int(fb), int(fb) + 1 },
             { (1.0 - (a - fa)) * scale, (a - fa) * scale, -(1.0 - (b - fb)) * scale,
               -(b - fb) * scale } };
}

/// How much a run's footprints through the part of the lens about (ux, uy)
/// scale the area of the surface it is on.
DEFOCUS_KERNEL double area_scale(double ux, double uy, const PixelRun& run)
{
    return std::max(0.0, 1.0 + ux * run.slope[0] + uy * run.slope[1]);
}

/// Adds one pixel's light `value` through cell `s` at (cx, cy), window
/// coordinates, radius r.
DEFOCUS_KERNEL void spread_pixel(const ApertureCell& s, double cx, double cy, double r,
                                 const d4& value, int w, int h, double* deltas, size_t stride)
{
    const double xa = cx + r * s.u0, xb = cx + r * s.u1;
    const double ya = cy + r * s.v0, yb = cy + r * s.v1;
    const AxisDeltas xs = axis_deltas(std::min(xa, xb), std::max(xa, xb), 0.0, w);
    const AxisDeltas ys = axis_deltas(std::min(ya, yb), std::max(ya, yb), 0.0, h);
    for (int j = 0; j < 4; ++j) {
        const double wy = ys.weight[j];
        if (wy == 0.0)
            continue;
        double* out = deltas + size_t(ys.at[j]) * stride;
        for (int k = 0; k < 4; ++k) {
            double* p = out + size_t(xs.at[k]) * 4;
            store4(p, load4(p) + splat(xs.weight[k] * wy) * value);
        }
    }
}

/// Adds a run of pixels of one radius r, window columns [x0, x1), through
/// cell `s`, their light scaled by `scale`: their x deltas are the same
/// taps at every pixel, so the run is filtered along the row once into
/// `line`, and the line added to the cell's rows. Deltas left of the window
/// add up at its first column (the rectangles cut there), and those right
/// of it are dropped.
DEFOCUS_KERNEL void spread_run(const ApertureCell& s, int x0, int x1, double cy, double r,
                               const float* rgba, double scale, int w, int h, double* deltas,
                               size_t stride, std::vector<double>& line)
{
    const double ua = 0.5 + r * s.u0, ub = 0.5 + r * s.u1;
    const AxisDeltas taps = axis_deltas(std::min(ua, ub), std::max(ua, ub), -INFINITY, INFINITY);
    const int span = taps.at[3] - taps.at[0];
    const double ya = cy + r * s.v0, yb = cy + r * s.v1;
    const AxisDeltas ys = axis_deltas(std::min(ya, yb), std::max(ya, yb), 0.0, h);
    // Entry i of the line gathers tap k from pixel i - offset[k]: built
    // by adding each pixel's taps, neighbouring pixels would add to the
    // same entries one after another, each addition waiting for the last.
    // The pixels are read as they are (float) and scaled as they are read.
    const int length = x1 - x0, n = length + span + 1;
    line.resize(size_t(n) * 4);
    double* l = line.data();
    const d4 scaled = splat(scale);
    auto value = [&](int j) { return load4(rgba + size_t(j) * 4) * scaled; };
    int offset[4];
    d4 weight[4];
    for (int k = 0; k < 4; ++k) {
        offset[k] = taps.at[k] - taps.at[0];
        weight[k] = splat(taps.weight[k]);
    }
    auto gather_edge = [&](int i) {
        d4 sum = splat(0.0);
        for (int k = 0; k < 4; ++k)
            if (const int j = i - offset[k]; j >= 0 && j < length)
                sum += weight[k] * value(j);
        store4(l + size_t(i) * 4, sum);
    };
    const int inner_begin = std::min(span, length), inner_end = std::max(inner_begin, length);
    for (int i = 0; i < inner_begin; ++i)
        gather_edge(i);
    for (int i = inner_begin; i < inner_end; ++i)
        store4(l + size_t(i) * 4, weight[0] * value(i - offset[0]) + weight[1] * value(i - offset[1])
                                      + weight[2] * value(i - offset[2])
                                      + weight[3] * value(i - offset[3]));
    for (int i = inner_end; i < n; ++i)
        gather_edge(i);
    // Line entry i lands at window column base + i, in the rows of the
    // y taps; those of no weight are left out. Each entry is read once
    // for all the rows.
    const int base = x0 + taps.at[0];
    const int cut = std::clamp(-base, 0, n), end = std::clamp(w + 2 - base, cut, n);
    d4 left = splat(0.0);
    for (int i = 0; i < cut; ++i)
        left += load4(l + size_t(i) * 4);
    double* rows[4];
    d4 row_weight[4];
    int count = 0;
    for (int j = 0; j < 4; ++j)
        if (ys.weight[j] != 0.0) {
            rows[count] = deltas + size_t(ys.at[j]) * stride;
            row_weight[count++] = splat(ys.weight[j]);
        }
    if (cut > 0)
        for (int j = 0; j < count; ++j)
            store4(rows[j], load4(rows[j]) + row_weight[j] * left);
    // With the count known, the rows stay in registers (most runs take 4).
    auto add_to_rows = [&](auto rows_count) {
        for (int i = cut; i < end; ++i) {
            const d4 entry = load4(l + size_t(i) * 4);
            for (int j = 0; j < int(rows_count); ++j) {
                double* o = rows[j] + size_t(base + i) * 4;
                store4(o, load4(o) + row_weight[j] * entry);
            }
        }
    };
    if (count == 4)
        add_to_rows(std::integral_constant<int, 4>());
    else
        add_to_rows(count);
}

/// How far light lands from its pixel along one axis, through the part of
/// the lens [a, b] along it, for signed radii in `radii`.
struct Offsets {
    double low, high;
};

Offsets offsets(const float* radii, double a, double b)
{
    const double ends[4] = { radii[0] * a, radii[0] * b, radii[1] * a, radii[1] * b };
    return { *std::min_element(ends, ends + 4), *std::max_element(ends, ends + 4) };
}

DEFOCUS_CLONES
void spread_pixels(const SignedLayer& layer, const ApertureCell& cell, const OIIO::ROI& window,
                   double* deltas, size_t stride, std::vector<double>& line)
{
    // Only pixels whose footprint through this cell can touch the window:
    // the deltas of one wholly outside it cancel.
    const Offsets ox = offsets(layer.radii, cell.u0, cell.u1),
                  oy = offsets(layer.radii, cell.v0, cell.v1);
    const int y_begin = std::max(layer.roi.ybegin, int(std::floor(window.ybegin - oy.high)) - 2),
              y_end = std::min(layer.roi.yend, int(std::ceil(window.yend - oy.low)) + 2);
    const int x_begin = std::max(layer.roi.xbegin, int(std::floor(window.xbegin - ox.high)) - 2),
              x_end = std::min(layer.roi.xend, int(std::ceil(window.xend - ox.low)) + 2);
    const int w = window.width(), h = window.height();
    const size_t width = size_t(layer.roi.width());
    const double ux = 0.5 * (cell.u0 + cell.u1), uy = 0.5 * (cell.v0 + cell.v1);
    for (int y = y_begin; y < y_end; ++y) {
        const size_t row = size_t(y - layer.roi.ybegin);
        const double cy = y + 0.5 - window.ybegin;
        for (size_t k = layer.row_runs[row]; k < layer.row_runs[row + 1]; ++k) {
            const PixelRun& run = layer.runs[k];
            const double r = run.radius;
            const double far = std::abs(r) * layer.extent + 1.0;
            const int begin = std::max(run.x_begin, x_begin), end = std::min(run.x_end, x_end);
            if (begin >= end || cy + far < 0.0 || cy - far > h)
                continue;
            const size_t first = row * width + size_t(begin - layer.roi.xbegin);
            const float* rgba = layer.color + first * 4;
            const double scale = area_scale(ux, uy, run);
            const int wx0 = begin - window.xbegin, wx1 = end - window.xbegin;
            // A run costs its length plus its footprint's width, a pixel
            // alone 4 times its length.
            const double footprint = std::abs(r * (cell.u1 - cell.u0));
            if (wx1 - wx0 >= 4 && 4.0 * (wx1 - wx0) > footprint) {
                spread_run(cell, wx0, wx1, cy, r, rgba, scale, w, h, deltas, stride, line);
                continue;
            }
            for (int px = wx0; px < wx1; ++px)
                spread_pixel(cell, px + 0.5, cy, r, load4(rgba + size_t(px - wx0) * 4) * splat(scale),
                             w, h, deltas, stride);
        }
    }
}

/// Adds a row of deltas into the column sums, clearing it, and sums the
/// column sums along the row into `light`.
DEFOCUS_CLONES
void integrate_deltas(double* deltas, double* running, double* light, int width, int pixels)
{
    d4 sum = splat(0.0);
    for (int x = 0; x < pixels; ++x) {
        d4 column = load4(running + x * 4) + load4(deltas + x * 4);
        store4(running + x * 4, column);
        store4(deltas + x * 4, splat(0.0));
        if (x < width) {
            sum += column;
            store4(light + x * 4, sum);
        }
    }
}

/// Runs are cut where the radius moves by an eighth of a pixel. A surface
/// whose depth changes along a row would otherwise be spread pixel by
/// pixel (16 corner taps each, against a run's 8); its footprints' edges
/// through a cell move by at most 1/16 pixel, and the whole aperture's
/// light that the change is taken against is made from the same runs.
///
/// One conversion instruction rounds it (to nearest, ties to even):
/// std::round is a library call, and this runs at every lit pixel.
float quantized(float radius)
{
    return float(_mm_cvtss_si64(_mm_set_ss(radius * 8.0f))) / 8.0f;
}

bool is_lit(const float* rgba)
{
    return rgba[0] != 0.0f || rgba[1] != 0.0f || rgba[2] != 0.0f || rgba[3] != 0.0f;
}

/// The radius changes by more than this from one pixel to the next only
/// across a step in depth, which is no slope of one surface.
constexpr float step_in_radius = 1.0f;

/// The radius's slope at pixel i from its neighbours before and after it
/// (i itself where there is none), among those lit and on its surface.
float slope(const float* rgba, const float* radius, size_t i, size_t before, size_t after)
{
    auto on_surface = [&](size_t j) {
        return j != i && is_lit(rgba + j * 4) && std::abs(radius[j] - radius[i]) < step_in_radius;
    };
    const bool b = on_surface(before), a = on_surface(after);
    if (a && b)
        return 0.5f * (radius[after] - radius[before]);
    if (a)
        return radius[after] - radius[i];
    if (b)
        return radius[i] - radius[before];
    return 0.0f;
}

/// The runs of a block of rows, and the ranges of their radii quantized
/// and as they were.
struct BlockRuns {
    std::vector<PixelRun> runs;
    float lowest = INFINITY, highest = -INFINITY;  ///< quantized
    float least = INFINITY, most = -INFINITY;

    void add_ranges(const BlockRuns& other)
    {
        lowest = std::min(lowest, other.lowest);
        highest = std::max(highest, other.highest);
        least = std::min(least, other.least);
        most = std::max(most, other.most);
    }
};

/// The runs of lit pixels of one quantized radius in rows [first, end) of
/// `roi` (from its top), and each row's count of them in counts[row].
BlockRuns find_runs(const OIIO::ROI& roi, const float* rgba, const float* radius, size_t first,
                    size_t end, size_t* counts)
{
    const size_t width = size_t(roi.width());
    BlockRuns block;
    // The ranges are kept in locals: a pixel's store to them would wait
    // for the last.
    float lowest = INFINITY, highest = -INFINITY, least = INFINITY, most = -INFINITY;
    for (size_t y = first; y < end; ++y) {
        const size_t row = y * width, before = block.runs.size();
        auto lit = [&](size_t i) { return is_lit(rgba + (row + i) * 4); };
        for (size_t x = 0; x < width;) {
            if (!lit(x)) {
                ++x;
                continue;
            }
            const float r = quantized(radius[row + x]);
            size_t run_end = x;
            do {
                least = std::min(least, radius[row + run_end]);
                most = std::max(most, radius[row + run_end]);
                ++run_end;
            } while (run_end < width && quantized(radius[row + run_end]) == r && lit(run_end));
            block.runs.push_back({ roi.xbegin + int(x), roi.xbegin + int(run_end), r });
            lowest = std::min(lowest, r);
            highest = std::max(highest, r);
            x = run_end;
        }
        counts[y] = block.runs.size() - before;
    }
    block.lowest = lowest;
    block.highest = highest;
    block.least = least;
    block.most = most;
    return block;
}

}  // namespace

void SignedLayer::set(const OIIO::ROI& pixels, const float* rgba, const float* radius,
                      float aperture_extent, int nthreads)
{
    roi = pixels;
    color = rgba;
    extent = aperture_extent;
    const size_t width = size_t(roi.width()), height = size_t(roi.height());
    // Blocks of rows find their runs side by side; row_runs first counts
    // each row's, and the blocks are then joined in order.
    constexpr size_t block_rows = 32;
    const size_t blocks = (height + block_rows - 1) / block_rows;
    std::vector<BlockRuns> found(blocks);
    row_runs.assign(height + 1, 0);
    parallel_for_each_item(0, int64_t(blocks), [&](int64_t b) {
        const size_t first = size_t(b) * block_rows;
        found[b] = find_runs(roi, rgba, radius, first, std::min(height, first + block_rows),
                             row_runs.data());
    }, nthreads);
    runs.clear();
    size_t total = 0;
    for (size_t y = 0; y < height; ++y)
        total += std::exchange(row_runs[y], total);
    row_runs.back() = total;
    runs.reserve(total);
    for (const BlockRuns& block : found)
        runs.insert(runs.end(), block.runs.begin(), block.runs.end());
    lit = OIIO::ROI();
    for (size_t y = 0; y < height; ++y)
        if (row_runs[y + 1] > row_runs[y]) {
            const int row = roi.ybegin + int(y);
            const OIIO::ROI line(runs[row_runs[y]].x_begin, runs[row_runs[y + 1] - 1].x_end, row,
                                 row + 1);
            lit = lit.defined() ? OIIO::roi_union(lit, line) : line;
        }
    BlockRuns all;
    for (const BlockRuns& block : found)
        all.add_ranges(block);
    radii[0] = all.lowest <= all.highest ? all.lowest : 0.0f;
    radii[1] = all.lowest <= all.highest ? all.highest : 0.0f;
    if (all.least >= all.most)
        return;
    parallel_for_each_item(0, int64_t(height), [&](int64_t row) {
        const size_t y = size_t(row);
        auto along_at = [&](size_t x) {
            const size_t i = y * width + x;
            return slope(rgba, radius, i, x > 0 ? i - 1 : i, x + 1 < width ? i + 1 : i);
        };
        for (size_t k = row_runs[y]; k < row_runs[y + 1]; ++k) {
            PixelRun& run = runs[k];
            const int length = run.x_end - run.x_begin;
            const size_t first = size_t(run.x_begin - roi.xbegin), last = first + length - 1;
            // A run's inner pixels have their neighbours on their surface,
            // so their central differences add up to the ends'.
            const float* r = radius + y * width;
            double along = along_at(first), down = 0.0;
            if (last > first)
                along += along_at(last) + 0.5 * (r[last] + r[last - 1] - r[first] - r[first + 1]);
            for (size_t x = first; x <= last; ++x) {
                const size_t i = y * width + x;
                down += slope(rgba, radius, i, y > 0 ? i - width : i,
                              y + 1 < height ? i + width : i);
            }
            run.slope[0] = float(along / length);
            run.slope[1] = float(down / length);
        }
    }, nthreads);
}

namespace {

/// How far from a pixel a layer's footprints reach, and their corner
/// deltas a pixel past their edge.
int footprint_margin(float reach)
{
    return int(std::ceil(reach)) + 2;
}

/// `roi` and footprint_margin() around it.
OIIO::ROI grown_by_footprints(const OIIO::ROI& roi, float reach)
{
    const int r = footprint_margin(reach);
    return OIIO::ROI(roi.xbegin - r, roi.xend + r, roi.ybegin - r, roi.yend + r);
}

}  // namespace

OIIO::ROI SignedLayer::light() const
{
    return lit.defined() ? grown_by_footprints(lit, reach()) : lit;
}

OIIO::ROI SignedLayer::sources_of(const OIIO::ROI& window) const
{
    return grown_by_footprints(window, reach());
}

void SignedLayer::solid_in(const OIIO::ROI& window, std::vector<uint8_t>& solid) const
{
    solid.assign(size_t(window.npixels()), 0);
    // Only pixels whose every source lies within the lit box can be solid.
    const int r = footprint_margin(reach());
    if (!lit.defined())
        return;
    const OIIO::ROI inner = OIIO::roi_intersection(
        window, OIIO::ROI(lit.xbegin + r, lit.xend - r, lit.ybegin + r, lit.yend - r));
    if (!has_pixels(inner))
        return;
    // A pixel is whole if it is lit, opaque, and its radius steps to no
    // neighbour's on its left or above: a step in depth opens a real gap
    // through some part of the lens. `counts` holds how many pixels are
    // not whole in the rectangle from the grown corner to each pixel, so
    // that any square's count is four reads.
    const OIIO::ROI grown = sources_of(inner);
    const int width = grown.width() + 1;
    std::vector<int32_t> counts(size_t(width) * (grown.height() + 1), 0);
    std::vector<float> above(size_t(grown.width()), NAN), here(above.size());
    for (int y = grown.ybegin; y < grown.yend; ++y) {
        std::fill(here.begin(), here.end(), NAN);
        const size_t row = size_t(y - roi.ybegin);
        for (size_t k = row_runs[row]; k < row_runs[row + 1]; ++k)
            for (int x = std::max(runs[k].x_begin, grown.xbegin);
                 x < std::min(runs[k].x_end, grown.xend); ++x)
                if (color[(row * roi.width() + (x - roi.xbegin)) * 4 + 3] >= 1.0f - 1e-3f)
                    here[size_t(x - grown.xbegin)] = runs[k].radius;
        const int32_t* sums_above = &counts[size_t(y - grown.ybegin) * width];
        int32_t* sums = &counts[size_t(y - grown.ybegin + 1) * width];
        int32_t along = 0;
        for (size_t i = 0; i < here.size(); ++i) {
            const bool whole = !std::isnan(here[i])
                               && !(i > 0 && std::abs(here[i] - here[i - 1]) >= step_in_radius)
                               && !(std::abs(here[i] - above[i]) >= step_in_radius);
            along += !whole;
            sums[i + 1] = sums_above[i + 1] + along;
        }
        std::swap(above, here);
    }
    const int side = 2 * r + 1;
    for (int y = 0; y < inner.height(); ++y) {
        const int32_t* top = &counts[size_t(y) * width];
        const int32_t* bottom = &counts[size_t(y + side) * width];
        uint8_t* out = &solid[size_t(y + inner.ybegin - window.ybegin) * window.width()
                              + size_t(inner.xbegin - window.xbegin)];
        for (int x = 0; x < inner.width(); ++x)
            out[x] = bottom[x + side] - bottom[x] - top[x + side] + top[x] == 0;
    }
}

OIIO::ROI SignedLayer::light_in(const OIIO::ROI& window) const
{
    if (!lit.defined())
        return OIIO::ROI(window.xbegin, window.xbegin, window.ybegin, window.ybegin);
    return OIIO::roi_intersection(light(), window);
}

void CellBand::reset(const OIIO::ROI& window)
{
    m_window = window;
    m_stride = (size_t(window.width()) + 2) * 4;
    m_deltas.assign(m_stride * (size_t(window.height()) + 2), 0.0);
    m_running.assign(m_stride, 0.0);
    m_row.assign(size_t(window.width()) * 4, 0.0);
}

void CellBand::spread(const SignedLayer& layer, const ApertureCell& cell)
{
    m_box = layer.light_in(m_window);
    spread_pixels(layer, cell, m_window, m_deltas.data(), m_stride, m_line);
}

const double* CellBand::integrate_row(int row)
{
    // Columns left of the box hold no light of this layer, and the box
    // ends at least two columns before the deltas' last column.
    const size_t first = size_t(m_box.xbegin - m_window.xbegin) * 4;
    integrate_deltas(&m_deltas[size_t(row) * m_stride + first], &m_running[first],
                     &m_row[first], m_box.width(), m_box.width() + 2);
    return m_row.data();
}

void CellBand::clear_rows(int first, int end)
{
    std::fill(m_deltas.begin() + ptrdiff_t(first) * ptrdiff_t(m_stride),
              m_deltas.begin() + ptrdiff_t(end) * ptrdiff_t(m_stride), 0.0);
}

}  // namespace defocus
