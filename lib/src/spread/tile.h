// Internal: the output tiles spreading accumulates, and the
// half-resolution grid some blocks are spread on.
#pragma once

#include "spread/block_levels.h"
#include "util/simd.h"

namespace defocus {

/// The output rows and columns one task accumulates: a tile of deltas
/// that stays in the second-level cache while every source row within
/// reach adds to it.
constexpr int tile_rows = 64, tile_columns = 256;
/// Every source pixel within reach of a tile is visited for it, so a box
/// reaching far, whose pixels all take this path, gets tiles a few times
/// its reach on a side: fewer visits outweigh a tile that leaves the cache.
constexpr int box_tile_reaches = 4, box_tile_limit = 2048;

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

/// The half-resolution pixels that pixels [begin, end) of a row or column
/// interpolate: half-resolution pixel i is centred between pixels 2 i and
/// 2 i + 1, so pixel x lies between i = floor((x - 1) / 2) and i + 1, a
/// quarter of the way from the nearer one.
struct HalfSpan {
    int begin, end;
};

inline HalfSpan half_span(int begin, int end)
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

}  // namespace defocus
