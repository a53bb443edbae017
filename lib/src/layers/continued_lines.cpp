#include "layers/continued_lines.h"

#include <algorithm>
#include <cmath>

#include <OpenImageIO/parallel.h>

#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// The lines' directions, as lattice steps so that each ray's first
/// observed pixel follows from its neighbour's: half a turn in 16 steps of
/// 7 to 18 degrees, so a stripe at any angle runs within 9.2 degrees of
/// one (a 4 px stripe drifts less than 2 px across a 10 px hole).
constexpr int line_directions = 12;
constexpr int line_step[line_directions][2] = {
    { 1, 0 },  { 3, 1 },  { 2, 1 },  { 1, 1 },   { 1, 2 },   { 1, 3 },
    { 0, 1 },  { -1, 3 }, { -1, 2 }, { -1, 1 },  { -2, 1 },  { -3, 1 } };

/// How unlike two observations are, relative to their level: colour and
/// coverage, and depth where both are covered.
float disagreement(const float a[5], const float b[5])
{
    float diff = 0.0f, level = 0.0f;
    for (int i = 0; i < 4; ++i) {
        diff += std::abs(a[i] - b[i]);
        level += 0.5f * (std::abs(a[i]) + std::abs(b[i]));
    }
    float d = diff / std::max(level, 1e-3f);
    if (a[3] > 0.0f && b[3] > 0.0f) {
        const float za = a[4] / a[3], zb = b[4] / b[3];
        d += std::abs(za - zb) / std::max(std::min(za, zb), 1e-6f);
    }
    return d;
}

/// The disagreement of a line's ends at which its estimate weighs 1/e
/// against the smooth fill's (garden scores move by 0.03 dB between 0.1
/// and 1).
constexpr float trust_scale = 0.25f;

/// How many observed pixels beyond each end of a line show whether the
/// surface runs along it.
constexpr int straight_run = 4;

}  // namespace

ContinuedLines::ContinuedLines(const FloatPixels& color, const FloatPixels& depth,
                               const std::vector<uint8_t>& holes, const ROI& window,
                               int max_length, int nthreads)
    : m_color(color)
    , m_depth(depth)
    , m_holes(holes)
    , m_window(window)
    , m_max_length(std::clamp(max_length, 0, 65535))
    , m_slot(window.npixels(), 0)
{
    for (int y = window.ybegin; y < window.yend; ++y)
        for (int x = window.xbegin; x < window.xend; ++x)
            if (hidden(x, y)) {
                m_estimates.emplace_back();
                m_slot[index(x, y)] = uint32_t(m_estimates.size());
            }
    if (m_estimates.empty() || m_max_length < 2)
        return;
    std::vector<uint16_t> forward, backward;
    for (const auto& step : line_step) {
        parallel_for(0, 2, [&](int64_t backwards) {
            if (backwards)
                steps_to_observed(-step[0], -step[1], backward);
            else
                steps_to_observed(step[0], step[1], forward);
        }, by_rows(nthreads));
        add_lines(step[0], step[1], forward, backward, nthreads);
    }
}

int ContinuedLines::reach(int max_length)
{
    return max_length + 2 * straight_run + 1;
}

bool ContinuedLines::hidden(int x, int y) const
{
    const ROI& roi = m_color.roi();
    return m_holes[size_t(y - roi.ybegin) * roi.width() + (x - roi.xbegin)] != 0;
}

size_t ContinuedLines::index(int x, int y) const
{
    return size_t(y - m_window.ybegin) * m_window.width() + (x - m_window.xbegin);
}

bool ContinuedLines::at(int x, int y, float value[5], float& trust) const
{
    const uint32_t slot = m_slot[index(x, y)];
    if (!slot || !(m_estimates[slot - 1].weight > 0.0f))
        return false;
    const Estimate& e = m_estimates[slot - 1];
    for (int i = 0; i < 5; ++i)
        value[i] = e.sum[i] / e.weight;
    trust = std::exp(-e.best / trust_scale);
    return true;
}

void ContinuedLines::steps_to_observed(int dx, int dy, std::vector<uint16_t>& steps) const
{
    // steps[p]: how many steps of (dx, dy) from hidden pixel p reach the
    // first observed pixel, 0 when none does within the window and
    // max_length. Each pixel's count follows from the next pixel's, so the
    // rows (or, along a row, the pixels) are visited from that end: one
    // pass whatever the holes' width.
    steps.assign(m_window.npixels(), 0);
    const int limit = int(m_max_length / std::hypot(dx, dy));
    const bool from_bottom = dy > 0 || (dy == 0 && dx > 0);
    for (int i = 0; i < m_window.height(); ++i) {
        const int y = from_bottom ? m_window.yend - 1 - i : m_window.ybegin + i;
        const int v = y + dy;
        if (v < m_window.ybegin || v >= m_window.yend)
            continue;
        for (int n = 0; n < m_window.width(); ++n) {
            const int x = dx > 0 ? m_window.xend - 1 - n : m_window.xbegin + n;
            const int u = x + dx;
            if (u < m_window.xbegin || u >= m_window.xend || !m_slot[index(x, y)])
                continue;
            const int k = !hidden(u, v) ? 1 : steps[index(u, v)] ? steps[index(u, v)] + 1 : 0;
            steps[index(x, y)] = uint16_t(k <= limit ? k : 0);
        }
    }
}

void ContinuedLines::observation(int x, int y, float value[5]) const
{
    const float* c = m_color(x, y);
    std::copy(c, c + 4, value);
    value[4] = c[3] > 0.0f ? c[3] * std::min(*m_depth(x, y), 1e30f) : 0.0f;
}

float ContinuedLines::end_of_ray(int x, int y, int dx, int dy, int steps, float end[5]) const
{
    // The ray's first observed pixel, and how much the surface changes
    // along the ray's direction over the next few beyond it: a structure
    // continues along a line only where it runs along that line outside
    // the hole too (the isophote direction of Criminisi et al. 2004), not
    // where the line cuts across stripes that happen to match at both ends.
    int u = x + steps * dx, v = y + steps * dy;
    observation(u, v, end);
    float change = 0.0f, previous[5], next[5];
    std::copy(end, end + 5, previous);
    for (int n = 1; n < straight_run; ++n) {
        u += dx;
        v += dy;
        if (!m_window.contains(u, v) || hidden(u, v))
            break;
        observation(u, v, next);
        change += disagreement(previous, next);
        std::copy(next, next + 5, previous);
    }
    return change;
}

void ContinuedLines::add_lines(int dx, int dy, const std::vector<uint16_t>& forward,
                               const std::vector<uint16_t>& backward, int nthreads)
{
    const float step = float(std::hypot(dx, dy));
    parallel_for(m_window.ybegin, m_window.yend, [&](int y) {
        for (int x = m_window.xbegin; x < m_window.xend; ++x) {
            const size_t p = index(x, y);
            const int kf = forward[p], kb = backward[p];
            if (!kf || !kb || (kf + kb) * step > m_max_length)
                continue;
            float a[5], b[5];
            float m = end_of_ray(x, y, dx, dy, kf, a) + end_of_ray(x, y, -dx, -dy, kb, b)
                      + disagreement(a, b);
            // The ends' neighbours across the line must agree too: a line
            // that meets the same stripe at both ends by chance (periodic
            // texture) does not continue it.
            for (int side = -1; side <= 1; side += 2) {
                const int ax = x + kf * dx - side * dy, ay = y + kf * dy + side * dx;
                const int bx = x - kb * dx - side * dy, by = y - kb * dy + side * dx;
                if (!m_window.contains(ax, ay) || !m_window.contains(bx, by) || hidden(ax, ay)
                    || hidden(bx, by))
                    continue;
                float pa[5], pb[5];
                observation(ax, ay, pa);
                observation(bx, by, pb);
                m += disagreement(pa, pb);
            }
            // A soft minimum over the lines: each weighs exp(-m / tau)
            // relative to the best so far, and less the longer it is.
            constexpr float tau = 0.05f;
            Estimate& e = m_estimates[m_slot[p] - 1];
            if (m < e.best) {
                const float rescale = std::isfinite(e.best) ? std::exp(-(e.best - m) / tau) : 0.0f;
                for (float& s : e.sum)
                    s *= rescale;
                e.weight *= rescale;
                e.best = m;
            }
            const float w = std::exp(-(m - e.best) / tau) / ((kf + kb) * step);
            const float t = float(kb) / float(kf + kb);  // 0 at b's end, 1 at a's
            for (int i = 0; i < 5; ++i)
                e.sum[i] += w * (t * a[i] + (1 - t) * b[i]);
            e.weight += w;
        }
    }, by_rows(nthreads));
}

}  // namespace defocus
