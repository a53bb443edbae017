// Internal: rows of pixels or blocks to spread, as runs that share a
// footprint program.
#pragma once

#include <algorithm>
#include <vector>

#include "spread/block_levels.h"
#include "spread/footprint_program.h"
#include "spread/spread_engine.h"
#include "spread/tile.h"

namespace defocus {

/// Consecutive pixels or blocks (a block's width apart) that share a
/// footprint program, program k of `family`: n of them from anchor column
/// x, their colours from
/// index `at` of a colour array. When they all blend the program's two
/// sizes alike (one radius: a plane, a sky), the run keeps that blend `t`
/// and 4 values per item; otherwise 4 values per item on the smaller size
/// and then 4 per item on the larger one.
struct ProgramRun {
    int x, n, k, at;
    float t;
    bool blended;
    const ProgramFamily* family;
};

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
    /// Appends a run of n items of program k of `family`, blending its sizes by t
    /// alike (folded) or not (blended), and returns where its colours go:
    /// 4 values per item, then for a blended run 4 more per item on the
    /// larger size.
    double* add_run(int x, int n, int k, float t, bool blended, const ProgramFamily* family)
    {
        longest = std::max(longest, n);
        runs.push_back({ x, n, k, int(color.size()), blended ? 0.0f : t, blended, family });
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
    /// Of blocks of grid_block() grid pixels: their reach and which program
    /// a radius takes.
    const ProgramFamily* family = nullptr;
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

/// The runs of a row of items (2^shift columns apart, their footprints
/// reaching `reach`) that can touch the tile's columns: [first, last).
struct RunsInReach {
    std::vector<ProgramRun>::const_iterator first, last;
    int x_lo, x_hi;  ///< the anchors whose footprints touch the columns
    bool empty() const { return first == last; }
};

inline RunsInReach runs_in_reach(const ItemRow& items, int shift, const Reach& reach, const Tile& tile)
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

}  // namespace defocus
