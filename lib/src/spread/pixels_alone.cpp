#include "spread/pixels_alone.h"

#include <algorithm>

#include "spread/block_levels.h"
#include "util/parallel_rows.h"

namespace defocus {

namespace {

/// The levels whose blocks spread a uniform block's exact footprint (see
/// max_box): larger ones spread a softened shape from their centre, which
/// no lone pixel's footprint adds up with anyway, and a highlight would
/// send up to 1,024 pixels of theirs the slow way.
constexpr int exact_block_levels = 2;
static_assert(1 << exact_block_levels == max_box, "the levels of exact block footprints");

/// Per level from 1 to exact_block_levels, the blocks of 2^level pixels
/// (aligned on multiples of their size, as the engine merges them) that
/// hold a pixel kept exact.
class BlocksWithExact {
public:
    BlocksWithExact(const SpreadSource& source, const uint8_t* kept_exact, int nthreads)
    {
        const OIIO::ROI& roi = source.roi;
        m_levels.resize(exact_block_levels + 1);
        for (int l = 1; l <= exact_block_levels; ++l) {
            Level& level = m_levels[size_t(l)];
            level.x0 = floor_shift(roi.xbegin, l);
            level.y0 = floor_shift(roi.ybegin, l);
            level.columns = floor_shift(roi.xend - 1, l) - level.x0 + 1;
            level.marked.assign(size_t(level.columns) * (floor_shift(roi.yend - 1, l) - level.y0 + 1),
                                0);
        }
        // By rows of the largest blocks, which no two tasks share.
        const int top = m_levels.back().y0, rows = int(m_levels.back().marked.size())
                                                       / m_levels.back().columns;
        parallel_for_each_item(0, rows, [&](int64_t row) {
            const int y0 = std::max(roi.ybegin, (top + int(row)) * (1 << exact_block_levels)),
                      y1 = std::min(roi.yend, (top + int(row) + 1) * (1 << exact_block_levels));
            for (int y = y0; y < y1; ++y) {
                const uint8_t* kept = kept_exact + size_t(y - roi.ybegin) * roi.width();
                for (int x = roi.xbegin; x < roi.xend; ++x)
                    if (kept[x - roi.xbegin])
                        for (int l = 1; l <= exact_block_levels; ++l)
                            m_levels[size_t(l)].block(x, y, l) = 1;
            }
        }, nthreads);
    }

    /// Whether the block of level `level` holding pixel (x, y) holds a
    /// pixel kept exact.
    bool at(int level, int x, int y) { return m_levels[size_t(level)].block(x, y, level); }

private:
    struct Level {
        int x0 = 0, y0 = 0, columns = 0;
        std::vector<uint8_t> marked;
        uint8_t& block(int x, int y, int level)
        {
            return marked[size_t(floor_shift(y, level) - y0) * columns
                          + size_t(floor_shift(x, level) - x0)];
        }
    };
    std::vector<Level> m_levels;
};

}  // namespace

void add_pixels_alone(const SpreadSource& source, std::vector<uint8_t>& kept, int nthreads)
{
    const OIIO::ROI& roi = source.roi;
    BlocksWithExact marked(source, kept.data(), nthreads);
    parallel_for_each_item(roi.ybegin, roi.yend, [&](int64_t y) {
        const size_t row = size_t(y - roi.ybegin) * roi.width();
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t p = row + size_t(x - roi.xbegin);
            // Its block of the largest size first: most hold no highlight.
            if (kept[p] || !marked.at(exact_block_levels, x, int(y))
                || is_zero(source.color + p * 4))
                continue;
            // The larger of its levels: its block at the smaller one lies
            // within that block.
            Component levels[2];
            const int count = components(SpreadMethod::Bounded, source.radius[p], false, levels);
            const int level = levels[count - 1].level;
            kept[p] = level > 0 && level <= exact_block_levels && marked.at(level, x, int(y));
        }
    }, nthreads);
}

}  // namespace defocus
