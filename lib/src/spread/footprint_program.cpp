#include "spread/footprint_program.h"

#include <algorithm>
#include <cmath>

namespace defocus {

FootprintProgram::FootprintProgram(const std::vector<RowSpan>& smaller, double smaller_area,
                                   const std::vector<RowSpan>& larger, double larger_area,
                                   int box)
{
    // The anchor pixel covers [0, 1); a pixel's shape is centred on its
    // centre, 0.5. A span's edges fall between columns floor(0.5 + edge)
    // and the next. The box's pixels are offset from the anchor by
    // `first` .. `last` in each direction.
    const int first = box == 1 ? 0 : 1 - box / 2, last = box / 2;
    // A shape has at least one span (the pixel itself at the smallest size).
    int last_row = smaller.front().row;
    m_first_row = last_row;
    m_first_column = int(std::floor(0.5 + smaller.front().left));
    m_last_column = m_first_column + 1;
    for (const std::vector<RowSpan>* spans : { &smaller, &larger })
        for (const RowSpan& s : *spans) {
            m_first_row = std::min(m_first_row, s.row);
            last_row = std::max(last_row, s.row);
            m_first_column = std::min(m_first_column, int(std::floor(0.5 + s.left)));
            m_last_column = std::max(m_last_column, int(std::floor(0.5 + s.right)) + 1);
        }
    m_first_row += first;
    last_row += last;
    m_first_column += first;
    m_last_column += last;
    // Deltas summed in place: the box's copies of a pixel's spans share
    // columns.
    const int rows = last_row - m_first_row + 1;
    const int columns = m_last_column - m_first_column + 1;
    std::vector<double> weights[2] = { std::vector<double>(size_t(rows) * columns, 0.0),
                                       std::vector<double>(size_t(rows) * columns, 0.0) };
    // A span's edges as four deltas, each edge split over the two columns
    // it falls between in proportion to its coverage, for every pixel of
    // the box.
    auto add = [&](const std::vector<RowSpan>& spans, double area, std::vector<double>& out) {
        for (const RowSpan& s : spans) {
            const double a = 0.5 + s.left, b = 0.5 + s.right;
            const double ia = std::floor(a), ib = std::floor(b);
            const double fa = a - ia, fb = b - ib;
            const double w = s.weight / (area * box * box);
            const double step[4] = { (1.0 - fa) * w, fa * w, -(1.0 - fb) * w, -fb * w };
            const int at[4] = { int(ia), int(ia) + 1, int(ib), int(ib) + 1 };
            for (int dy = first; dy <= last; ++dy) {
                double* row = &out[size_t(s.row + dy - m_first_row) * columns - m_first_column];
                for (int e = 0; e < 4; ++e)
                    for (int dx = first; dx <= last; ++dx)
                        row[at[e] + dx] += step[e];
            }
        }
    };
    add(smaller, smaller_area, weights[0]);
    add(larger, larger_area, weights[1]);
    // Runs of adjacent non-zero deltas are the clusters.
    m_row_begin.assign(size_t(rows) + 1, 0);
    for (int r = 0; r < rows; ++r) {
        bool open = false;
        for (int c = 0; c < columns; ++c) {
            const double w0 = weights[0][size_t(r) * columns + c];
            const double w1 = weights[1][size_t(r) * columns + c];
            if (w0 == 0.0 && w1 == 0.0) {
                open = false;
                continue;
            }
            if (open) {
                ++m_clusters.back().taps;
            } else {
                m_clusters.push_back({ m_first_column + c, 1, int32_t(m_smaller.size()) });
                ++m_row_begin[size_t(r) + 1];
                open = true;
            }
            m_smaller.push_back(w0);
            m_larger.push_back(w1);
        }
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

const FootprintProgram& ProgramFamily::build(int k) const
{
    std::lock_guard<std::mutex> lock(m_mutex);
    if (!m_owned[k]) {
        std::vector<RowSpan> smaller, larger;
        const double a0 = m_profile->rows(k * m_bin_width, smaller);
        const double a1 = m_profile->rows((k + 1) * m_bin_width, larger);
        const int box = m_block <= max_box ? m_block : 2;
        m_owned[k] = std::make_unique<FootprintProgram>(smaller, a0, larger, a1, box);
        m_built[k].store(m_owned[k].get(), std::memory_order_release);
    }
    return *m_owned[k];
}

}  // namespace defocus
