#include "layers/continued_lines.h"

#include <algorithm>
#include <cmath>

#include <OpenImageIO/parallel.h>

#include "layers/observation.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// The lines' directions, as lattice steps so that each ray's first
/// observed pixel follows from its neighbour's: half a turn in 12 steps of
/// 8 to 18 degrees, so a stripe at any angle runs within 9.2 degrees of
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
                               const HoleMap& holes, const ROI& window,
                               int max_length, int nthreads)
    : m_color(color)
    , m_depth(depth)
    , m_holes(holes)
    , m_window(window)
    , m_max_length(std::clamp(max_length, 0, 65535))
    , m_words((window.width() + 63) / 64)
    , m_tracked(size_t(m_words) * window.height(), 0)
    , m_rank(m_tracked.size())
{
    // A line crosses a band of width w in at least w pixels, and the band's
    // row and column runs are at most sqrt(2) w: a hidden pixel whose row
    // and column runs are both longer lies where no line is short enough,
    // and it blocks the lines that reach it.
    const std::vector<uint8_t> wide = in_wide_holes(int(std::ceil(std::sqrt(2.0) * m_max_length)),
                                                    nthreads);
    // Numbered in raster order: each row's count, then its first number.
    std::vector<uint32_t>& first = m_first;
    first.assign(window.height() + 1, 0);
    parallel_for(0, window.height(), [&](int row) {
        uint64_t* bits = &m_tracked[size_t(row) * m_words];
        const int y = window.ybegin + row;
        for (int i = 0; i < window.width(); ++i)
            if (hidden(window.xbegin + i, y) && !wide[size_t(row) * window.width() + i])
                bits[i / 64] |= uint64_t(1) << (i % 64);
        uint32_t count = 0;
        for (int w = 0; w < m_words; ++w)
            count += uint32_t(__builtin_popcountll(bits[w]));
        first[row + 1] = count;
    }, by_rows(nthreads));
    for (size_t r = 1; r < first.size(); ++r)
        first[r] += first[r - 1];
    m_pixels.resize(first.back());
    m_estimates.resize(first.back());
    parallel_for(0, window.height(), [&](int row) {
        uint32_t n = first[row];
        for (int w = 0; w < m_words; ++w) {
            const size_t word = size_t(row) * m_words + w;
            m_rank[word] = n;
            for (uint64_t bits = m_tracked[word]; bits; bits &= bits - 1)
                m_pixels[n++] = { window.xbegin + 64 * w + __builtin_ctzll(bits),
                                  window.ybegin + row };
        }
    }, by_rows(nthreads));
    if (m_estimates.empty() || m_max_length < 2)
        return;
    std::vector<uint16_t> forward, backward;
    std::vector<float> line_disagreement;
    for (const auto& step : line_step) {
        parallel_for(0, 2, [&](int64_t backwards) {
            if (backwards)
                steps_to_observed(-step[0], -step[1], backward);
            else
                steps_to_observed(step[0], step[1], forward);
        }, by_rows(nthreads));
        add_lines(step[0], step[1], forward, backward, line_disagreement, nthreads);
    }
}

std::vector<uint8_t> ContinuedLines::in_wide_holes(int limit, int nthreads) const
{
    // Column runs first, in blocks of columns that share cache lines, then
    // row runs: 1 where both are longer than `limit`.
    const int width = m_window.width(), height = m_window.height();
    std::vector<uint8_t> wide(m_window.npixels(), 0);
    constexpr int block = 64;
    parallel_for(0, (width + block - 1) / block, [&](int b) {
        const int x0 = b * block, x1 = std::min(x0 + block, width);
        std::vector<int> run_start(x1 - x0, -1);
        for (int y = 0; y <= height; ++y)
            for (int x = x0; x < x1; ++x) {
                const bool is_hidden = y < height
                                       && hidden(m_window.xbegin + x, m_window.ybegin + y);
                int& start = run_start[x - x0];
                if (is_hidden && start < 0)
                    start = y;
                else if (!is_hidden && start >= 0) {
                    if (y - start > limit)
                        for (int r = start; r < y; ++r)
                            wide[size_t(r) * width + x] = 1;
                    start = -1;
                }
            }
    }, by_rows(nthreads));
    parallel_for(0, height, [&](int y) {
        uint8_t* row = &wide[size_t(y) * width];
        for (int x = 0; x < width;) {
            if (!hidden(m_window.xbegin + x, m_window.ybegin + y)) {
                ++x;
                continue;
            }
            int end = x;
            while (end < width && hidden(m_window.xbegin + end, m_window.ybegin + y))
                ++end;
            if (end - x <= limit)
                std::fill(row + x, row + end, uint8_t(0));
            x = end;
        }
    }, by_rows(nthreads));
    return wide;
}

int ContinuedLines::reach(int max_length)
{
    return max_length + 2 * straight_run + 1;
}

uint32_t ContinuedLines::slot(int x, int y) const
{
    if (!hidden(x, y))
        return 0;
    const int i = x - m_window.xbegin;
    const size_t word = size_t(y - m_window.ybegin) * m_words + i / 64;
    const uint64_t bit = uint64_t(1) << (i % 64);
    if (!(m_tracked[word] & bit))
        return blocked;
    return m_rank[word] + uint32_t(__builtin_popcountll(m_tracked[word] & (bit - 1))) + 1;
}

bool ContinuedLines::at(int x, int y, float value[5], float& trust) const
{
    const uint32_t slot = this->slot(x, y);
    if (!slot || slot == blocked || !(m_estimates[slot - 1].weight > 0.0f))
        return false;
    const Estimate& e = m_estimates[slot - 1];
    for (int i = 0; i < 5; ++i)
        value[i] = e.sum[i] / e.weight;
    trust = std::exp(-e.best / trust_scale);
    return true;
}

void ContinuedLines::steps_to_observed(int dx, int dy, std::vector<uint16_t>& steps) const
{
    // steps[i]: how many steps of (dx, dy) from hidden pixel i reach the
    // first observed pixel, 0 when none does within the window and
    // max_length. Each pixel's count follows from that of the pixel one
    // step on, so the hidden pixels are visited in raster order from that
    // end: one pass over them whatever the holes' width.
    // The pixel one step on is found by walking its row's tracked pixels
    // alongside, as x + dx moves the same way as x.
    steps.assign(m_pixels.size(), 0);
    const int limit = int(m_max_length / std::hypot(dx, dy));
    const bool from_end = dy > 0 || (dy == 0 && dx > 0);
    const int height = m_window.height();
    for (int n = 0; n < height; ++n) {
        const int row = from_end ? height - 1 - n : n, next_row = row + dy;
        if (next_row < 0 || next_row >= height)
            continue;
        const int v = m_window.ybegin + next_row;
        const uint32_t lo = m_first[next_row], hi = m_first[next_row + 1];
        uint32_t j = from_end ? hi : lo;  // the walk through row next_row
        const uint32_t count = m_first[row + 1] - m_first[row];
        for (uint32_t c = 0; c < count; ++c) {
            const uint32_t i = from_end ? m_first[row + 1] - 1 - c : m_first[row] + c;
            const int u = m_pixels[i].x + dx;
            if (u < m_window.xbegin || u >= m_window.xend)
                continue;
            int k = 1;
            if (hidden(u, v)) {
                // Tracked, or in a wide hole, which blocks the line.
                bool tracked;
                uint32_t next;
                if (from_end) {
                    while (j > lo && m_pixels[j - 1].x > u)
                        --j;
                    tracked = j > lo && m_pixels[j - 1].x == u;
                    next = j - 1;
                } else {
                    while (j < hi && m_pixels[j].x < u)
                        ++j;
                    tracked = j < hi && m_pixels[j].x == u;
                    next = j;
                }
                k = tracked && steps[next] ? steps[next] + 1 : 0;
            }
            steps[i] = uint16_t(k <= limit ? k : 0);
        }
    }
}

void ContinuedLines::observation(int x, int y, float value[5]) const
{
    observe(m_color, m_depth, x, y, value);
}

float ContinuedLines::change_beyond(int x, int y, int dx, int dy, const float end[5]) const
{
    // How much the surface changes along the ray's direction over the few
    // observed pixels beyond its end (x, y): a structure continues along a
    // line only where it runs along that line outside the hole too (the
    // isophote direction of Criminisi et al. 2004), not where the line
    // cuts across stripes that happen to match at both ends.
    float change = 0.0f, previous[5], next[5];
    std::copy(end, end + 5, previous);
    for (int n = 1; n < straight_run; ++n) {
        x += dx;
        y += dy;
        if (!m_window.contains(x, y) || hidden(x, y))
            break;
        observation(x, y, next);
        change += disagreement(previous, next);
        std::copy(next, next + 5, previous);
    }
    return change;
}

float ContinuedLines::disagreement_of_line(int ax, int ay, int bx, int by, int dx, int dy) const
{
    float a[5], b[5];
    observation(ax, ay, a);
    observation(bx, by, b);
    float m = disagreement(a, b);
    // The ends' neighbours across the line must agree too: a line that
    // meets the same stripe at both ends by chance (periodic texture) does
    // not continue it.
    for (int side = -1; side <= 1; side += 2) {
        const int pax = ax - side * dy, pay = ay + side * dx;
        const int pbx = bx - side * dy, pby = by + side * dx;
        if (!m_window.contains(pax, pay) || !m_window.contains(pbx, pby) || hidden(pax, pay)
            || hidden(pbx, pby))
            continue;
        float pa[5], pb[5];
        observation(pax, pay, pa);
        observation(pbx, pby, pb);
        m += disagreement(pa, pb);
    }
    return m + change_beyond(ax, ay, dx, dy, a) + change_beyond(bx, by, -dx, -dy, b);
}

void ContinuedLines::add_lines(int dx, int dy, const std::vector<uint16_t>& forward,
                               const std::vector<uint16_t>& backward,
                               std::vector<float>& line_disagreement, int nthreads)
{
    // Every hidden pixel on a line between the same two ends shares its
    // disagreement: it is found once, at the line's first pixel.
    const float step = float(std::hypot(dx, dy));
    auto crosses = [&](int64_t i) {
        return forward[i] && backward[i] && (forward[i] + backward[i]) * step <= m_max_length;
    };
    line_disagreement.resize(m_pixels.size());
    parallel_for(int64_t(0), int64_t(m_pixels.size()), [&](int64_t i) {
        if (backward[i] != 1 || !crosses(i))
            return;
        const int x = m_pixels[i].x, y = m_pixels[i].y, kf = forward[i];
        line_disagreement[i] = disagreement_of_line(x + kf * dx, y + kf * dy, x - dx, y - dy,
                                                    dx, dy);
    }, paropt(nthreads));

    parallel_for(int64_t(0), int64_t(m_pixels.size()), [&](int64_t i) {
        if (!crosses(i))
            return;
        const int x = m_pixels[i].x, y = m_pixels[i].y;
        const int kf = forward[i], kb = backward[i];
        const float m = line_disagreement[slot(x - (kb - 1) * dx, y - (kb - 1) * dy) - 1];
        // A soft minimum over the lines: each weighs exp(-m / tau)
        // relative to the best so far, and less the longer it is. A line
        // 20 tau worse than the best, or untrusted by exp(-10), adds
        // nothing.
        constexpr float tau = 0.05f;
        Estimate& e = m_estimates[i];
        if (!(m < std::min(e.best + 20.0f * tau, 10.0f * trust_scale)))
            return;
        if (m < e.best) {
            const float rescale = std::isfinite(e.best) ? std::exp(-(e.best - m) / tau) : 0.0f;
            for (float& s : e.sum)
                s *= rescale;
            e.weight *= rescale;
            e.best = m;
        }
        float a[5], b[5];
        observation(x + kf * dx, y + kf * dy, a);
        observation(x - kb * dx, y - kb * dy, b);
        const float w = std::exp(-(m - e.best) / tau) / ((kf + kb) * step);
        const float t = float(kb) / float(kf + kb);  // 0 at b's end, 1 at a's
        for (int c = 0; c < 5; ++c)
            e.sum[c] += w * (t * a[c] + (1 - t) * b[c]);
        e.weight += w;
    }, paropt(nthreads));
}

}  // namespace defocus
