#include "footprint_program.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace defocus {

FootprintProgram::FootprintProgram(const std::vector<RowSpan>& smaller, double smaller_area,
                                   const std::vector<RowSpan>& larger, double larger_area)
{
    struct Delta {
        int row, column;
        double weight[2];
    };
    std::vector<Delta> all;
    // A span's edges as four deltas of one size, each edge split over the
    // two columns it falls between in proportion to its coverage. The
    // anchor pixel covers [0, 1); the shape's centre is at its centre, 0.5.
    auto add = [&](const std::vector<RowSpan>& spans, double area, int size) {
        for (const RowSpan& s : spans) {
            const double a = 0.5 + s.left, b = 0.5 + s.right;
            const double ia = std::floor(a), ib = std::floor(b);
            const double fa = a - ia, fb = b - ib;
            const double w = s.weight / area;
            const std::pair<int, double> edges[4] = { { int(ia), (1.0 - fa) * w },
                                                      { int(ia) + 1, fa * w },
                                                      { int(ib), -(1.0 - fb) * w },
                                                      { int(ib) + 1, -fb * w } };
            for (const auto& [column, weight] : edges) {
                Delta d { s.row, column, { 0.0, 0.0 } };
                d.weight[size] = weight;
                all.push_back(d);
            }
        }
    };
    add(smaller, smaller_area, 0);
    add(larger, larger_area, 1);
    auto key = [](const Delta& d) { return std::make_pair(d.row, d.column); };
    std::sort(all.begin(), all.end(),
              [&](const Delta& a, const Delta& b) { return key(a) < key(b); });
    std::vector<Delta> merged;
    for (const Delta& d : all) {
        if (!merged.empty() && key(merged.back()) == key(d)) {
            merged.back().weight[0] += d.weight[0];
            merged.back().weight[1] += d.weight[1];
        } else {
            merged.push_back(d);
        }
    }
    // A shape has at least one span (the pixel itself at the smallest size).
    m_first_row = merged.front().row;
    m_row_begin.assign(merged.back().row - m_first_row + 2, 0);
    m_first_column = m_last_column = merged.front().column;
    for (size_t i = 0; i < merged.size(); ++i) {
        const Delta& d = merged[i];
        m_first_column = std::min(m_first_column, d.column);
        m_last_column = std::max(m_last_column, d.column);
        const bool adjacent = i > 0 && merged[i - 1].row == d.row
                              && merged[i - 1].column + 1 == d.column;
        if (adjacent) {
            ++m_clusters.back().taps;
        } else {
            m_clusters.push_back({ d.column, 1, int32_t(m_smaller.size()) });
            ++m_row_begin[d.row - m_first_row + 1];
        }
        m_smaller.push_back(d.weight[0]);
        m_larger.push_back(d.weight[1]);
    }
    for (size_t r = 1; r < m_row_begin.size(); ++r)
        m_row_begin[r] += m_row_begin[r - 1];
}

Footprint FootprintProgram::footprint(double t) const
{
    Footprint fp;
    fp.x0 = m_first_column;
    fp.y0 = m_first_row;
    fp.width = m_last_column - m_first_column + 1;
    fp.height = last_row() - first_row() + 1;
    fp.weights.assign(size_t(fp.width) * fp.height, 0.0);
    for (int row = first_row(); row <= last_row(); ++row) {
        double* w = &fp.weights[size_t(row - fp.y0) * fp.width];
        for (const DeltaCluster* c = begin(row); c != end(row); ++c)
            for (int i = 0; i < c->taps; ++i)
                w[c->column + i - fp.x0] += (1.0 - t) * m_smaller[c->at + i]
                                            + t * m_larger[c->at + i];
        for (int i = 1; i < fp.width; ++i)
            w[i] += w[i - 1];
    }
    return fp;
}

ProgramFamily::ProgramFamily(std::shared_ptr<const RowProfile> profile, int block,
                             double bin_width, double max_radius)
    : m_profile(std::move(profile))
    , m_block(block)
    , m_bin_width(bin_width)
    , m_bins_per_pixel(1.0 / bin_width)
    , m_min_bin(0.5 / bin_width)
    , m_max_bin(std::max(0.5, max_radius) / bin_width)
    , m_built(size_t(m_max_bin) + 1)
    , m_owned(m_built.size())
{
}

ProgramFamily::~ProgramFamily() = default;

double ProgramFamily::block_spans(double r, std::vector<RowSpan>& spans) const
{
    std::vector<RowSpan> pixel;
    const double area = m_profile->rows(r, pixel);
    if (m_block == 1) {
        spans = std::move(pixel);
        return area;
    }
    spans.clear();
    for (int dy = 1 - m_block / 2; dy <= m_block / 2; ++dy)
        for (int dx = 1 - m_block / 2; dx <= m_block / 2; ++dx)
            for (RowSpan span : pixel) {
                span.row += dy;
                span.left += dx;
                span.right += dx;
                spans.push_back(span);
            }
    return area * m_block * m_block;
}

const FootprintProgram& ProgramFamily::build(int k) const
{
    std::lock_guard<std::mutex> lock(m_mutex);
    if (!m_owned[k]) {
        std::vector<RowSpan> smaller, larger;
        const double a0 = block_spans(k * m_bin_width, smaller);
        const double a1 = block_spans((k + 1) * m_bin_width, larger);
        m_owned[k] = std::make_unique<FootprintProgram>(smaller, a0, larger, a1);
        m_built[k].store(m_owned[k].get(), std::memory_order_release);
    }
    return *m_owned[k];
}

}  // namespace defocus
