#include "spread/layer_survey.h"

#include <algorithm>
#include <climits>
#include <cmath>

#include "spread/block_levels.h"

namespace defocus {

using OIIO::ROI;

namespace {

/// The pixels of one block row of one sparse level, summed per block and
/// program as they come, pixel row by pixel row; then made into runs.
class BlockRowSums {
public:
    /// Starts block row `block_row` of `blocks` blocks of `size` pixels
    /// from block first_block, their footprints from `families`.
    void start(int first_block, int blocks, int block_row, int size, FamilyFinder& families)
    {
        m_first = first_block;
        m_size = size;
        m_centre_y = (block_row + 0.5) * size;
        m_families = &families;
        m_sums.assign(size_t(blocks), Sum {});
        m_others.clear();
    }

    /// Adds `value`, from a pixel of radius r, to block `b` on program k,
    /// blending its sizes by t.
    DEFOCUS_KERNEL void add(int b, int k, float t, float r, const d4& value)
    {
        Sum* sum = &m_sums[size_t(b - m_first)];
        const ProgramFamily* family = sum->family;
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
            sum->family = family ? family
                                 : m_families->at((b + 0.5) * m_size, m_centre_y, m_size, r);
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
        const ProgramFamily* family = nullptr;  ///< of the block's footprints
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
            while (j < all.size() && all[j].k == all[i].k && all[j].family == all[i].family
                   && all[j].b == all[j - 1].b + 1)
                ++j;
            const bool folded = std::all_of(all.begin() + i, all.begin() + j, [&](const Sum& e) {
                return !e.blended && e.t == all[i].t;
            });
            const int count = int(j - i);
            double* out = row.add_run(level.anchor(all[i].b), count, all[i].k, all[i].t, !folded,
                                      all[i].family);
            for (size_t e = i; e < j; ++e, out += 4)
                for (int ch = 0; ch < 4; ++ch) {
                    out[ch] = folded ? all[e].smaller[ch] + all[e].larger[ch] : all[e].smaller[ch];
                    if (!folded)
                        out[size_t(count) * 4 + ch] = all[e].larger[ch];
                }
            i = j;
        }
    }

    int m_first = 0, m_size = 1;
    double m_centre_y = 0.0;
    FamilyFinder* m_families = nullptr;
    std::vector<Sum> m_sums;    ///< per block, its first program
    std::vector<Sum> m_others;  ///< other programs of a block
};

}  // namespace

/// Pixel p's colour (at column x, radius r) and those after it in its
/// block of 2^level columns (the smaller of its two block sizes) that go
/// alike: along a row a block's pixels
/// mostly do (one radius, none kept exact), so they are summed here, in
/// registers, and go to the blocks once. x moves to the last one summed.
DEFOCUS_KERNEL d4 alike_in_block(const SpreadSource& source, size_t p, int& x, int level, float r)
{
    d4 value = load4(source.color + p * 4);
    const int block_end = std::min(source.roi.xend, (floor_shift(x, level) + 1) * (1 << level));
    for (size_t q = p + 1; x + 1 < block_end; ++q, ++x) {
        const float* u = source.color + q * 4;
        if (is_zero(u) || source.radius[q] != r || (source.keep_exact && source.keep_exact[q]))
            break;
        value += load4(u);
    }
    return value;
}

DEFOCUS_CLONES
void survey_rows(const SpreadSource& source, SpreadMethod method, const ShapePrograms* shape,
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
    std::vector<FamilyFinder> families;
    for (int l = 0; l < nlevels; ++l)
        families.emplace_back(*shape, levels[l]->grid_shift(), source.cateye_side);
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
            const d4 value = c[0].level > 0 ? alike_in_block(source, p, x, c[0].level, r)
                                            : load4(v);
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
                    sums[l].start(first, floor_shift(roi.xend - 1, l) - first + 1, by, 1 << l,
                                  families[l]);
                }
                sums[l].add(floor_shift(x, l), blend[i].k, blend[i].t, r,
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

}  // namespace defocus
