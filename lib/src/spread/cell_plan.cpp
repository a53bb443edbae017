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

/// Light that varies less than this (premultiplied, scene-linear) over a
/// blur's reach is the same through every part of the lens.
constexpr float light_tolerance = 1e-3f;

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
/// of its shapes: the mean run of opaque (alpha ≥ 1/2) or of clear pixels,
/// whichever is shorter, along rows or columns, whichever is shorter.
struct TileStats {
    std::vector<float> low, high;  ///< 4 a tile: R, G, B, A
    std::vector<float> radius;
    std::vector<uint8_t> lit;
    std::vector<float> width;
};

/// Counts of a tile's opaque and clear pixels and of the changes between
/// them along rows and along columns.
struct Runs {
    int opaque = 0, clear = 0, along_rows = 0, along_columns = 0;

    float width() const
    {
        const int shorter = std::min(opaque, clear);
        float w = float(CellTiles::size);
        if (along_rows > 0)
            w = std::min(w, 2.0f * shorter / along_rows);
        if (along_columns > 0)
            w = std::min(w, 2.0f * shorter / along_columns);
        return std::max(w, 1.0f);
    }
};

TileStats layer_stats(const SignedLayer& layer, const TileGrid& grid, int nthreads)
{
    const size_t n = size_t(grid.columns) * grid.rows;
    TileStats stats { std::vector<float>(n * 4, 0.0f), std::vector<float>(n * 4, 0.0f),
                      std::vector<float>(n, 0.0f), std::vector<uint8_t>(n, 0),
                      std::vector<float>(n, float(CellTiles::size)) };
    // Tiles the layer covers whole start from their first pixel; those it
    // covers in part keep the 0 of the pixels it lacks.
    std::vector<uint8_t> seen(n, 0);
    std::vector<Runs> runs(n);
    const int size = CellTiles::size;
    const OIIO::ROI& roi = layer.roi;
    // Each row of tiles is its own task: its pixels write only its tiles.
    parallel_for_each_item(grid.y0, grid.y0 + grid.rows, [&](int64_t tile_row) {
        const int ty = int(tile_row);
        const int tile_top = grid.anchor_y + ty * size;
        for (int y = std::max(roi.ybegin, tile_top); y < std::min(roi.yend, tile_top + size); ++y) {
            const float* rgba = layer.color + size_t(y - roi.ybegin) * roi.width() * 4;
            const float* above = y > roi.ybegin ? rgba - size_t(roi.width()) * 4 : nullptr;
            for (int x = roi.xbegin; x < roi.xend; ++x, rgba += 4) {
                const int tx = floor_div(x - grid.anchor_x, size);
                const size_t t = grid.index(tx, ty);
                const bool opaque = rgba[3] >= 0.5f;
                Runs& r = runs[t];
                (opaque ? r.opaque : r.clear) += 1;
                r.along_rows += x > roi.xbegin && (rgba[-1] >= 0.5f) != opaque;
                r.along_columns += above && (above[(x - roi.xbegin) * 4 + 3] >= 0.5f) != opaque;
                float* low = &stats.low[t * 4];
                float* high = &stats.high[t * 4];
                if (!seen[t]) {
                    seen[t] = 1;
                    const int tile_x = grid.anchor_x + tx * size;
                    if (tile_x >= roi.xbegin && tile_x + size <= roi.xend
                        && tile_top >= roi.ybegin && tile_top + size <= roi.yend)
                        for (int c = 0; c < 4; ++c)
                            low[c] = high[c] = rgba[c];
                }
                for (int c = 0; c < 4; ++c) {
                    low[c] = std::min(low[c], rgba[c]);
                    high[c] = std::max(high[c], rgba[c]);
                }
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
    return int(std::clamp(std::ceil(2.0 * radius / width), 4.0, double(most_cells_across)));
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
        const TileStats stats = layer_stats(layers[l], grid, nthreads);
        std::vector<float> occluded(n, 0.0f), varied(n, 0.0f);
        for (int ty = grid.y0; ty < grid.y0 + grid.rows; ++ty)
            for (int tx = grid.x0; tx < grid.x0 + grid.columns; ++tx) {
                float low[4] = { INFINITY, INFINITY, INFINITY, INFINITY },
                      high[4] = { -INFINITY, -INFINITY, -INFINITY, -INFINITY }, blur = 0.0f,
                      width = float(CellTiles::size);
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
                    varies |= high[c] - low[c] > light_tolerance;
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
