#include "layers/blur_field.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// Blurs closer than a pixel of CoC look alike.
constexpr float discontinuity = 1.0f;

}  // namespace

BlurField::BlurField(const Layer& flat, const CircleOfConfusion& coc, int nthreads)
    : m_roi(flat.color.roi())
    , m_color(flat.color, m_roi)
    , m_depth(flat.depth, ROI(m_roi.xbegin, m_roi.xend, m_roi.ybegin, m_roi.yend, 0, 1, 0, 1))
    , m_blur(m_roi.npixels())
    , m_discontinuity(m_roi.npixels(), 0)
{
    parallel_for(m_roi.ybegin, m_roi.yend, [&](int y) {
        for (int x = m_roi.xbegin; x < m_roi.xend; ++x)
            m_blur[index(x, y)] = m_color(x, y)[3] > 0.0f
                                      ? float(coc.diameter(depth(x, y), x, y))
                                      : std::numeric_limits<float>::quiet_NaN();
    }, by_rows(nthreads));
    // A pixel is at a discontinuity where any 3x3 neighbour's CoC differs
    // from its own by more than the threshold (NaN, nothing there, never
    // does).
    const int width = m_roi.width();
    parallel_for(0, m_roi.height(), [&](int y) {
        const float* rows[3];
        for (int j = 0; j < 3; ++j)
            rows[j] = &m_blur[size_t(std::clamp(y + j - 1, 0, m_roi.height() - 1)) * width];
        uint8_t* out = &m_discontinuity[size_t(y) * width];
        for (int x = 0; x < width; ++x) {
            const float own = rows[1][x];
            const int x0 = std::max(x - 1, 0), x1 = std::min(x + 1, width - 1);
            bool step = false;
            for (int j = 0; j < 3 && !step; ++j)
                for (int nx = x0; nx <= x1; ++nx)
                    step |= std::abs(rows[j][nx] - own) > discontinuity;
            out[x] = step;
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

}  // namespace defocus
