#include "layers/blur_field.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "util/fresh_array.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

BlurField::BlurField(const Layer& flat, const CircleOfConfusion& coc, int nthreads)
    : m_roi(flat.color.roi())
    , m_color(flat.color, m_roi)
    , m_depth(flat.depth, ROI(m_roi.xbegin, m_roi.xend, m_roi.ybegin, m_roi.yend, 0, 1, 0, 1))
    // Every value is written below.
    , m_blur(fresh_array<float>(m_roi.npixels(), nthreads))
    , m_discontinuity(fresh_array<uint8_t>(m_roi.npixels(), nthreads))
{
    // Per row, the least and largest CoC, reduced after.
    std::vector<std::pair<float, float>> ranges(m_roi.height(), { INFINITY, -INFINITY });
    parallel_for(m_roi.ybegin, m_roi.yend, [&](int y) {
        auto& [least, largest] = ranges[y - m_roi.ybegin];
        for (int x = m_roi.xbegin; x < m_roi.xend; ++x) {
            float& c = m_blur[index(x, y)];
            if (!(m_color(x, y)[3] > 0.0f)) {
                c = std::numeric_limits<float>::quiet_NaN();
                continue;
            }
            c = float(coc.diameter(depth(x, y), x, y));
            least = std::min(least, c);
            largest = std::max(largest, c);
        }
    }, by_rows(nthreads));
    for (const auto& [least, largest] : ranges) {
        m_least = std::min(m_least, least);
        m_largest = std::max(m_largest, largest);
    }
    // A pixel is at a discontinuity where any 3x3 neighbour's CoC differs
    // from its own by more than the threshold (NaN, nothing there, never
    // does): where the neighbourhood's largest CoC lies more than it above
    // its own, or the least more than it below. Rounding keeps the order
    // of differences, so this is the test of each neighbour, exactly.
    const int width = m_roi.width();
    parallel_for(0, m_roi.height(), [&](int y) {
        const float* rows[3];
        for (int j = 0; j < 3; ++j)
            rows[j] = &m_blur[size_t(std::clamp(y + j - 1, 0, m_roi.height() - 1)) * width];
        // Per column, the largest and least CoC of the three rows (NaN
        // compares false, so it never wins).
        std::vector<float> most(width), least(width);
        for (int x = 0; x < width; ++x) {
            float hi = -INFINITY, lo = INFINITY;
            for (const float* row : rows) {
                hi = row[x] > hi ? row[x] : hi;
                lo = row[x] < lo ? row[x] : lo;
            }
            most[x] = hi;
            least[x] = lo;
        }
        uint8_t* out = &m_discontinuity[size_t(y) * width];
        for (int x = 0; x < width; ++x) {
            const int x0 = std::max(x - 1, 0), x1 = std::min(x + 1, width - 1);
            const float hi = std::max({ most[x0], most[x], most[x1] });
            const float lo = std::min({ least[x0], least[x], least[x1] });
            const float own = rows[1][x];
            out[x] = hi - own > discontinuity_step || own - lo > discontinuity_step;
        }
    }, by_rows(nthreads));
}

float BlurField::other_side(int x, int y) const
{
    const float own = blur(x, y);
    float other = own;
    for (int ny = std::max(y - 1, m_roi.ybegin); ny <= std::min(y + 1, m_roi.yend - 1); ++ny)
        for (int nx = std::max(x - 1, m_roi.xbegin); nx <= std::min(x + 1, m_roi.xend - 1); ++nx)
            if (std::abs(blur(nx, ny) - own) > std::abs(other - own))
                other = blur(nx, ny);
    return other;
}

std::vector<BlurField> blur_fields(const Scene& scene, const CircleOfConfusion& coc, int nthreads)
{
    std::vector<BlurField> flats;
    flats.reserve(scene.flat.size());
    for (const Layer& flat : scene.flat)
        flats.emplace_back(flat, coc, nthreads);
    return flats;
}

}  // namespace defocus
