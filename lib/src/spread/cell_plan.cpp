#include "spread/cell_plan.h"

#include <algorithm>
#include <cmath>

#include "spread/block_levels.h"
#include "util/parallel_rows.h"

namespace defocus {

namespace {

/// Alpha closer than this is the same alpha: no part of the lens sees it
/// differently.
constexpr float alpha_tolerance = 1e-3f;

/// Light that varies less than this (premultiplied, scene-linear) plus
/// the relative tolerance times its brightest there, over a blur's reach,
/// is the same through every part of the lens. What cells change is a
/// fraction of that range, and 2% of a level is about one code value of
/// an 8-bit sRGB output at mid-grey (more below it): a dusk sky's
/// gradient behind a branch takes no cells.
constexpr float light_tolerance = 1e-3f;
constexpr float relative_light_tolerance = 0.02f;

/// The most cells across the aperture automatic cells take, and the
/// fewest where cells are taken at all.
constexpr int most_cells_across = 12;

/// A grid of tiles over pixels, anchored where the frame's tiles are.
struct TileGrid {
    int x0, y0;           ///< the grid's first tile, in tiles from the anchor
    int columns, rows;
    int anchor_x, anchor_y;

    size_t index(int tx, int ty) const { return size_t(ty - y0) * columns + (tx - x0); }
    bool inside(int tx, int ty) const
    {
        return tx >= x0 && tx < x0 + columns && ty >= y0 && ty < y0 + rows;
    }
};

/// What a layer holds in each tile of the grid: the range of each channel
/// (0 where it has no pixels), its largest blur where lit, and the width
/// of its shapes there (see ShapeRuns).
struct TileStats {
    std::vector<float> low, high;  ///< 4 a tile: R, G, B, A
    std::vector<float> radius;
    std::vector<uint8_t> lit;
    std::vector<float> width;
};

/// A tile's opaque (alpha ≥ 1/2) and clear pixels and, along rows and along
/// columns, how many runs of each they make: a run that passes through
/// several tiles counts in each by its share of pixels there. So a shape's
/// width is its runs' whole length, not the part of it a tile holds.
struct ShapeRuns {
    int opaque = 0, clear = 0;
    float opaque_runs[2] = { 0.0f, 0.0f }, clear_runs[2] = { 0.0f, 0.0f };  ///< rows, columns

    /// The mean run of opaque or of clear pixels, whichever is shorter,
    /// along rows or columns, whichever is shorter; infinite where the
    /// tile is all one or the other, or its runs all reach the frame's end.
    float width() const
    {
        float w = INFINITY;
        if (opaque == 0 || clear == 0)
            return w;
        for (int d = 0; d < 2; ++d) {
            if (opaque_runs[d] > 0.0f)
                w = std::min(w, opaque / opaque_runs[d]);
            if (clear_runs[d] > 0.0f)
                w = std::min(w, clear / clear_runs[d]);
        }
        return std::max(w, 1.0f);
    }

    /// Adds `pixels` of a run `length` pixels long along direction `d`.
    void add(bool opaque_run, int pixels, int length, int d)
    {
        (opaque_run ? opaque_runs[d] : clear_runs[d]) += float(pixels) / float(length);
    }
};

/// Calls `run(begin, end, opaque)` for each run of opaque or of clear
/// pixels among `count` alphas `stride` floats apart that ends within them
/// on both sides. Runs the data window cuts are left out: the frame ends
/// there, not the shape, and its width is unknown.
template<class Run>
void for_each_run(const float* alpha, int count, size_t stride, Run&& run)
{
    int begin = 0;
    for (int i = 1; i < count; ++i)
        if ((alpha[i * stride] >= 0.5f) != (alpha[(i - 1) * stride] >= 0.5f)) {
            if (begin > 0)
                run(begin, i, alpha[begin * stride] >= 0.5f);
            begin = i;
        }
}

/// Adds a run of pixels [begin, end) along direction `d` (coordinates
/// along it, tiles starting at `tile_start`) to the runs of the tiles it
/// passes, `tile_of(i)` giving the index of the tile of its pixel at i.
template<class TileOf>
void add_run(std::vector<ShapeRuns>& runs, int begin, int end, bool opaque, int d,
             int tile_start, TileOf&& tile_of)
{
    const int size = CellTiles::size;
    for (int i = begin; i < end;) {
        const int next = std::min(end, tile_start + (floor_div(i - tile_start, size) + 1) * size);
        runs[tile_of(i)].add(opaque, next - i, end - begin, d);
        i = next;
    }
}

/// Adds each tile's channel ranges, lit pixels and blur and, with
/// `shapes`, its opaque and clear pixels and their runs along rows.
void add_rows(const SignedLayer& layer, const TileGrid& grid, bool shapes, TileStats& stats,
              std::vector<ShapeRuns>& runs, int nthreads)
{
    // Tiles the layer covers whole start from their first pixel; those it
    // covers in part keep the 0 of the pixels it lacks.
    std::vector<uint8_t> seen(runs.size(), 0);
    const int size = CellTiles::size;
    const OIIO::ROI& roi = layer.roi;
    const size_t stride = size_t(roi.width()) * 4;
    auto tile_at = [&](int x, int y) {
        return grid.index(floor_div(x - grid.anchor_x, size), floor_div(y - grid.anchor_y, size));
    };
    // Each row of tiles is its own task: its pixels write only its tiles.
    parallel_for_each_item(grid.y0, grid.y0 + grid.rows, [&](int64_t tile_row) {
        const int ty = int(tile_row);
        const int tile_top = grid.anchor_y + ty * size;
        for (int y = std::max(roi.ybegin, tile_top); y < std::min(roi.yend, tile_top + size); ++y) {
            const float* rgba = layer.color + size_t(y - roi.ybegin) * stride;
            if (shapes)
                for_each_run(rgba + 3, roi.width(), 4, [&](int begin, int end, bool opaque) {
                    add_run(runs, roi.xbegin + begin, roi.xbegin + end, opaque, 0, grid.anchor_x,
                            [&](int x) { return tile_at(x, y); });
                });
            // A tile's part of the row at a time, its ranges kept in
            // registers (stored through a pointer, they would be stored
            // at every pixel: the pixels are floats too).
            for (int x = roi.xbegin; x < roi.xend;) {
                const int tx = floor_div(x - grid.anchor_x, size);
                const int tile_x = grid.anchor_x + tx * size;
                const int end = std::min(roi.xend, tile_x + size);
                const size_t t = grid.index(tx, ty);
                if (!seen[t]) {
                    seen[t] = 1;
                    if (tile_x >= roi.xbegin && tile_x + size <= roi.xend
                        && tile_top >= roi.ybegin && tile_top + size <= roi.yend)
                        for (int c = 0; c < 4; ++c)
                            stats.low[t * 4 + c] = stats.high[t * 4 + c] = rgba[c];
                }
                float low[4], high[4];
                for (int c = 0; c < 4; ++c) {
                    low[c] = stats.low[t * 4 + c];
                    high[c] = stats.high[t * 4 + c];
                }
                const int begin = x;
                int opaque = 0;
                for (; x < end; ++x, rgba += 4) {
                    opaque += rgba[3] >= 0.5f;
                    for (int c = 0; c < 4; ++c) {
                        low[c] = std::min(low[c], rgba[c]);
                        high[c] = std::max(high[c], rgba[c]);
                    }
                }
                for (int c = 0; c < 4; ++c) {
                    stats.low[t * 4 + c] = low[c];
                    stats.high[t * 4 + c] = high[c];
                }
                runs[t].opaque += opaque;
                runs[t].clear += end - begin - opaque;
            }
            const size_t row = size_t(y - roi.ybegin);
            for (size_t k = layer.row_runs[row]; k < layer.row_runs[row + 1]; ++k) {
                const PixelRun& run = layer.runs[k];
                for (int x = run.x_begin; x < run.x_end;) {
                    const int tx = floor_div(x - grid.anchor_x, size);
                    const size_t t = grid.index(tx, ty);
                    stats.lit[t] = 1;
                    stats.radius[t] = std::max(stats.radius[t], std::abs(run.radius));
                    x = grid.anchor_x + (tx + 1) * size;
                }
            }
        }
    }, nthreads);
}

/// Adds each tile's runs of opaque and of clear pixels down columns.
void add_column_runs(const SignedLayer& layer, const TileGrid& grid, std::vector<ShapeRuns>& runs,
                     int nthreads)
{
    const int size = CellTiles::size;
    const OIIO::ROI& roi = layer.roi;
    const size_t stride = size_t(roi.width()) * 4;
    // Bands of columns of tiles are tasks for the runs down columns. Each
    // reads its pixels row by row, each column's run open until its alpha
    // crosses 1/2 (a column at a time would read a cache line a pixel),
    // and adds them up in tiles of its own: tasks side by side would share
    // cache lines of `runs`.
    constexpr int band_tiles = 16;
    parallel_for_each_item(0, (grid.columns + band_tiles - 1) / band_tiles, [&](int64_t band) {
        const int first = grid.x0 + int(band) * band_tiles;
        const int tiles = std::min(band_tiles, grid.x0 + grid.columns - first);
        const int left = std::max(roi.xbegin, grid.anchor_x + first * size);
        const int right = std::min(roi.xend, grid.anchor_x + (first + tiles) * size);
        if (left >= right)
            return;
        std::vector<ShapeRuns> column(size_t(grid.rows) * tiles);
        std::vector<int> run_begin(size_t(right - left), 0);
        const float* alpha = layer.color + size_t(left - roi.xbegin) * 4 + 3;
        for (int y = 1; y < roi.height(); ++y, alpha += stride)
            for (int i = 0; i < right - left; ++i) {
                const bool opaque = alpha[i * 4] >= 0.5f;
                if ((alpha[stride + i * 4] >= 0.5f) == opaque)
                    continue;
                // As for_each_run: a run from the window's first row is cut.
                const int tile = floor_div(left + i - grid.anchor_x, size) - first;
                if (run_begin[i] > 0)
                    add_run(column, roi.ybegin + run_begin[i], roi.ybegin + y, opaque, 1,
                            grid.anchor_y, [&](int row) {
                                const int ty = floor_div(row - grid.anchor_y, size) - grid.y0;
                                return size_t(ty) * tiles + tile;
                            });
                run_begin[i] = y;
            }
        for (int ty = 0; ty < grid.rows; ++ty)
            for (int tile = 0; tile < tiles; ++tile) {
                const ShapeRuns& down = column[size_t(ty) * tiles + tile];
                ShapeRuns& r = runs[grid.index(first + tile, grid.y0 + ty)];
                r.opaque_runs[1] += down.opaque_runs[1];
                r.clear_runs[1] += down.clear_runs[1];
            }
    }, nthreads);
}

/// A layer's stats in each tile of `grid`; the widths of its shapes only
/// with `shapes` (else infinite).
TileStats layer_stats(const SignedLayer& layer, const TileGrid& grid, bool shapes, int nthreads)
{
    const size_t n = size_t(grid.columns) * grid.rows;
    TileStats stats { std::vector<float>(n * 4, 0.0f), std::vector<float>(n * 4, 0.0f),
                      std::vector<float>(n, 0.0f), std::vector<uint8_t>(n, 0),
                      std::vector<float>(n, INFINITY) };
    std::vector<ShapeRuns> runs(n);
    add_rows(layer, grid, shapes, stats, runs, nthreads);
    if (!shapes)
        return stats;
    add_column_runs(layer, grid, runs, nthreads);
    for (size_t t = 0; t < n; ++t)
        stats.width[t] = runs[t].width();
    return stats;
}

/// Marks in `map` the tiles within `reach` pixels of the 2 × 2 tiles from
/// tile (tx, ty).
void mark_reach(const TileGrid& grid, int tx, int ty, double reach, std::vector<float>& map,
                float value)
{
    const int d = int(std::ceil(reach / CellTiles::size));
    for (int y = std::max(grid.y0, ty - d); y <= std::min(grid.y0 + grid.rows - 1, ty + 1 + d);
         ++y)
        for (int x = std::max(grid.x0, tx - d);
             x <= std::min(grid.x0 + grid.columns - 1, tx + 1 + d); ++x) {
            float& m = map[grid.index(x, y)];
            m = std::max(m, value);
        }
}

/// A frame's cells cost about the number of cells times the tiles that
/// take them. Automatic cells stay within 16 a tile of the frame on
/// average, plus what 16 tiles of the most cells cost (so that a small
/// frame still resolves a thin occluder before a highlight): where the
/// tiles ask for more, the most cells a tile takes is lowered until they
/// fit.
void keep_within_budget(CellTiles& tiles)
{
    const int most = most_cells_across;
    const int64_t budget = 16 * tiles.count() + 16 * int64_t(most) * most;
    auto cost = [&](int cap) {
        int64_t sum = 0;
        for (uint8_t across : tiles.across)
            sum += int64_t(std::min<int>(across, cap)) * std::min<int>(across, cap);
        return sum;
    };
    int cap = most;
    while (cap > 2 && cost(cap) > budget)
        --cap;
    for (uint8_t& across : tiles.across)
        across = uint8_t(std::min<int>(across, cap));
}

}  // namespace

OIIO::ROI CellTiles::tile(int column, int row) const
{
    const int x = window.xbegin + column * size, y = window.ybegin + row * size;
    return OIIO::ROI(x, std::min(x + size, window.xend), y, std::min(y + size, window.yend), 0, 1,
                     0, 4);
}

int64_t CellTiles::with_cells() const
{
    return std::count_if(across.begin(), across.end(), [](uint8_t a) { return a > 1; });
}

int automatic_cells_across(double radius, double width)
{
    const double shapes = std::min(width, double(CellTiles::size));
    return int(std::clamp(std::ceil(2.0 * radius / shapes), 4.0, double(most_cells_across)));
}

CellTiles plan_cell_tiles(const std::vector<SignedLayer>& layers, const OIIO::ROI& window,
                          int cells, int nthreads)
{
    const int size = CellTiles::size;
    CellTiles tiles;
    tiles.window = window;
    tiles.columns = (window.width() + size - 1) / size;
    tiles.rows = (window.height() + size - 1) / size;
    tiles.across.assign(size_t(tiles.count()), 0);
    const int fixed = cells > 0 ? int(std::ceil(std::sqrt(double(cells)) - 1e-9)) : 0;
    if (fixed == 1 || layers.size() < 2 || tiles.count() == 0)
        return tiles;

    OIIO::ROI all = window;
    for (const SignedLayer& layer : layers)
        all = OIIO::roi_union(all, layer.roi);
    TileGrid grid;
    grid.anchor_x = window.xbegin;
    grid.anchor_y = window.ybegin;
    grid.x0 = floor_div(all.xbegin - window.xbegin, size);
    grid.y0 = floor_div(all.ybegin - window.ybegin, size);
    grid.columns = floor_div(all.xend - 1 - window.xbegin, size) - grid.x0 + 1;
    grid.rows = floor_div(all.yend - 1 - window.ybegin, size) - grid.y0 + 1;
    const size_t n = size_t(grid.columns) * grid.rows;

    // Back to front: `behind`, the tiles where a farther layer's light
    // differs between parts of the lens (it varies within its blur's
    // reach); `needed`, the cells across the lens a tile takes (0: none).
    // A layer varies in a tile where one of its channels does over the
    // tile and its neighbours.
    std::vector<float> behind(n, 0.0f), needed(n, 0.0f);
    for (size_t l = 0; l < layers.size(); ++l) {
        // The farthest layer occludes nothing: its shapes do not count.
        const TileStats stats = layer_stats(layers[l], grid, l > 0, nthreads);
        std::vector<float> occluded(n, 0.0f), varied(n, 0.0f);
        for (int ty = grid.y0; ty < grid.y0 + grid.rows; ++ty)
            for (int tx = grid.x0; tx < grid.x0 + grid.columns; ++tx) {
                float low[4] = { INFINITY, INFINITY, INFINITY, INFINITY },
                      high[4] = { -INFINITY, -INFINITY, -INFINITY, -INFINITY }, blur = 0.0f,
                      width = INFINITY;
                // The tile and those after it: a change at a border between
                // tiles is found once, by the tile before it.
                for (int y = ty; y <= ty + 1; ++y)
                    for (int x = tx; x <= tx + 1; ++x) {
                        if (!grid.inside(x, y))
                            continue;
                        const size_t t = grid.index(x, y);
                        for (int c = 0; c < 4; ++c) {
                            low[c] = std::min(low[c], stats.low[t * 4 + c]);
                            high[c] = std::max(high[c], stats.high[t * 4 + c]);
                        }
                        blur = std::max(blur, stats.radius[t]);
                        width = std::min(width, stats.width[t]);
                    }
                if (blur < sharp_radius)
                    continue;
                const double reach = blur * layers[l].extent + 1.0;
                if (high[3] - low[3] > alpha_tolerance)
                    mark_reach(grid, tx, ty, reach, occluded,
                               float(fixed ? fixed : automatic_cells_across(blur, width)));
                bool varies = false;
                for (int c = 0; c < 4; ++c)
                    varies |= high[c] - low[c]
                              > light_tolerance + relative_light_tolerance * high[c];
                if (varies)
                    mark_reach(grid, tx, ty, reach, varied, 1.0f);
            }
        if (l > 0)
            for (size_t t = 0; t < n; ++t)
                if (behind[t] > 0.0f)
                    needed[t] = std::max(needed[t], occluded[t]);
        for (size_t t = 0; t < n; ++t)
            behind[t] = std::max(behind[t], varied[t]);
    }
    for (int row = 0; row < tiles.rows; ++row)
        for (int column = 0; column < tiles.columns; ++column)
            tiles.across[size_t(row) * tiles.columns + column]
                = uint8_t(needed[grid.index(column, row)]);
    if (!fixed)
        keep_within_budget(tiles);
    return tiles;
}

}  // namespace defocus
