#include "layers/continued_patterns.h"

#include <algorithm>
#include <cmath>

#include <OpenImageIO/parallel.h>

#include "layers/observation.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// Observed pixels compared on each side of a run, along it.
constexpr int side_pixels = 5;

/// How far along its line a run's copy is searched, beyond the run's own
/// width: a period of the pattern must fit.
constexpr int search_reach = 64;

/// The widest run whose copy is trusted on the match of its own sides.
constexpr int widest_lone_run = 32;

/// The lines on either side of a wide run whose copies are compared with
/// its own.
constexpr int neighbour_lines = 6;

/// Side pixels covered less than this (beside a nearer edge, or the
/// layer's own edge) are not compared.
constexpr float min_side_coverage = 0.25f;

/// Where the best copy's sides differ from the run's by this share of
/// their own variation, it is trusted 1/e.
constexpr float copy_trust_scale = 0.1f;

/// How unlike two observations' colours are: squared differences of their
/// colour over their coverage. A pixel beside a nearer edge holds only the
/// part of its coverage the edge leaves, so its coverage is not compared.
float colour_difference(const float a[5], const float b[5])
{
    float diff = 0.0f;
    for (int c = 0; c < 3; ++c) {
        const float d = a[c] / a[3] - b[c] / b[3];
        diff += d * d;
    }
    return diff;
}

}  // namespace

int ContinuedPatterns::reach(int max_width)
{
    return max_width + search_reach + side_pixels + 2;
}

ContinuedPatterns::ContinuedPatterns(const FloatPixels& color, const FloatPixels& depth,
                                     const HoleMap& holes, const ROI& window, int max_width,
                                     int nthreads)
    : m_color(color)
    , m_depth(depth)
    , m_holes(holes)
    , m_window(window)
    , m_max_width(max_width)
{
    if (window.width() <= 0 || window.height() <= 0)
        return;
    continue_runs(true, m_row_copies, nthreads);
    continue_runs(false, m_column_copies, nthreads);
}

bool ContinuedPatterns::observed(int x, int y) const
{
    // Not a surface continued behind a nearer edge: that is made up too.
    return m_window.contains(x, y) && *m_holes.row(x, y) == HiddenPixels::seen;
}

void ContinuedPatterns::observation(int x, int y, float value[5]) const
{
    observe(m_color, m_depth, x, y, value);
}

/// One run of hidden pixels along a line: u along it, v across.
struct ContinuedPatterns::Run {
    int begin, end, v;
};

/// A seen pixel beside a run, at (u, v) of its line's axes.
/// The colours (over coverage) of a run's sides, widened by a tenth of
/// their spread.
struct ContinuedPatterns::ColourRange {
    float low[3] = { INFINITY, INFINITY, INFINITY }, high[3] = { -INFINITY, -INFINITY, -INFINITY };

    void add(const float value[5])
    {
        for (int c = 0; c < 3; ++c) {
            low[c] = std::min(low[c], value[c] / value[3]);
            high[c] = std::max(high[c], value[c] / value[3]);
        }
    }
    void widen()
    {
        for (int c = 0; c < 3; ++c) {
            const float margin = 0.1f * (high[c] - low[c]) + 1e-3f * std::abs(high[c]);
            low[c] -= margin;
            high[c] += margin;
        }
    }
    bool holds(int c, float v) const { return v >= low[c] && v <= high[c]; }
};

struct ContinuedPatterns::Sample {
    int u, v;
    float value[5];
};

void ContinuedPatterns::pixel(bool along_rows, int u, int v, int& x, int& y)
{
    x = along_rows ? u : v;
    y = along_rows ? v : u;
}

std::vector<ContinuedPatterns::Sample> ContinuedPatterns::sides(bool along_rows, const Run& run,
                                                                 float& nearest) const
{
    // Up to `side_pixels` seen pixels before and after the run, on its own
    // line and the two beside it on either side, from the second on: the
    // pixel next to the hole often holds some of the occluder's antialiased
    // edge.
    std::vector<Sample> found;
    nearest = INFINITY;
    for (int dv = -2; dv <= 2; ++dv)
        for (int k = 2; k <= side_pixels + 1; ++k)
            for (const int u : { run.begin - k, run.end - 1 + k }) {
                int x, y;
                pixel(along_rows, u, run.v + dv, x, y);
                if (!observed(x, y))
                    continue;
                Sample s { u, run.v + dv, {} };
                observation(x, y, s.value);
                if (s.value[3] < min_side_coverage)
                    continue;
                nearest = std::min(nearest, s.value[4] / s.value[3]);
                found.push_back(s);
            }
    return found;
}

float ContinuedPatterns::difference(bool along_rows, const Run& run,
                                    const std::vector<Sample>& sides, const ColourRange& range,
                                    int shift, float nearest,
                                    std::vector<float>& differences) const
{
    // The copy must be seen all along, no nearer than the run's sides, and
    // hold no colour the sides do not (a light from afar).
    for (int u = run.begin; u < run.end; ++u) {
        int x, y;
        pixel(along_rows, u + shift, run.v, x, y);
        if (!observed(x, y))
            return INFINITY;
        const float* c = m_color(x, y);
        if (c[3] > 0.0f && *m_depth(x, y) < 0.99f * nearest)
            return INFINITY;
        for (int i = 0; i < 3 && c[3] > 0.0f; ++i)
            if (!range.holds(i, c[i] / c[3]))
                return INFINITY;
    }
    differences.clear();
    for (const Sample& s : sides) {
        int x, y;
        pixel(along_rows, s.u + shift, s.v, x, y);
        if (!observed(x, y))
            continue;
        float other[5];
        observation(x, y, other);
        if (other[3] >= min_side_coverage)
            differences.push_back(colour_difference(other, s.value));
    }
    if (differences.size() < sides.size() * 3 / 4)
        return INFINITY;
    // The worst two are left out: a side pixel may be part of another
    // occluder's edge, or a speck.
    std::sort(differences.begin(), differences.end());
    const size_t kept = differences.size() - 2;
    float sum = 0.0f;
    for (size_t i = 0; i < kept; ++i)
        sum += differences[i];
    return sum / float(kept);
}

bool ContinuedPatterns::best_copy(bool along_rows, const Run& run, Copy& copy) const
{
    float nearest;
    const std::vector<Sample> found = sides(along_rows, run, nearest);
    if (found.size() < 2 * side_pixels)
        return false;
    // The sides' own variation: a plain surface needs no copy.
    float mean[5] = { 0, 0, 0, 1, 0 }, variation = 0.0f;
    for (const Sample& s : found)
        for (int c = 0; c < 3; ++c)
            mean[c] += s.value[c] / s.value[3] / float(found.size());
    for (const Sample& s : found)
        variation += colour_difference(s.value, mean);
    variation /= float(found.size());
    if (variation <= 1e-8f)
        return false;
    ColourRange range;
    for (const Sample& s : found)
        range.add(s.value);
    range.widen();
    const int width = run.end - run.begin, farthest = search_reach + width;
    std::vector<float> by_shift(size_t(2 * farthest + 1), INFINITY), differences;
    float best = INFINITY;
    for (int shift = -farthest; shift <= farthest; ++shift)
        if (std::abs(shift) >= width) {
            float& d = by_shift[size_t(shift + farthest)];
            d = difference(along_rows, run, found, range, shift, nearest, differences);
            best = std::min(best, d);
        }
    if (!std::isfinite(best))
        return false;
    // Where the sides do not pin the hole's content down (a checker's edge
    // anywhere between them matches), the shifts that match as well run
    // together: the middle of the nearest such range is taken.
    const float tied = best + 1e-3f * variation;
    int chosen = 0;
    bool any = false;
    for (int first = -farthest; first <= farthest;) {
        if (!(by_shift[size_t(first + farthest)] <= tied)) {
            ++first;
            continue;
        }
        int last = first;
        while (last + 1 <= farthest && by_shift[size_t(last + 1 + farthest)] <= tied)
            ++last;
        const int middle = (first + last) / 2;
        if (!any || std::abs(middle) < std::abs(chosen))
            chosen = middle;
        any = true;
        first = last + 1;
    }
    copy = { along_rows ? chosen : 0, along_rows ? 0 : chosen,
             std::exp(-best / (copy_trust_scale * variation)) };
    return std::isfinite(by_shift[size_t(chosen + farthest)]);
}

void ContinuedPatterns::continue_runs(bool along_rows,
                                      std::vector<std::vector<CopiedRun>>& copied, int nthreads)
{
    const int lines = along_rows ? m_window.height() : m_window.width();
    const int length = along_rows ? m_window.width() : m_window.height();
    const int u0 = along_rows ? m_window.xbegin : m_window.ybegin;
    const int v0 = along_rows ? m_window.ybegin : m_window.xbegin;
    auto hidden = [&](int u, int v) {
        int x, y;
        pixel(along_rows, u, v, x, y);
        return m_holes(x, y);
    };
    copied.assign(size_t(lines), {});
    parallel_for(0, lines, [&](int64_t line) {
        const int v = v0 + int(line);
        for (int u = u0; u < u0 + length;) {
            if (!hidden(u, v)) {
                ++u;
                continue;
            }
            Run run { u, u, v };
            while (run.end < u0 + length && hidden(run.end, v))
                ++run.end;
            u = run.end;
            const int width = run.end - run.begin;
            if (width > m_max_width)
                continue;
            Copy copy;
            // A wide run without a copy still counts against those beside it.
            if (!best_copy(along_rows, run, copy))
                copy = {};
            if (copy.trust > 0.0f || width > widest_lone_run)
                copied[size_t(line)].push_back({ run.begin, run.end, copy });
        }
    }, by_rows(nthreads));
    weigh_by_neighbours(along_rows, copied, nthreads);
}

void ContinuedPatterns::weigh_by_neighbours(bool along_rows,
                                            std::vector<std::vector<CopiedRun>>& copied,
                                            int nthreads)
{
    auto shift = [&](const Copy& copy) { return along_rows ? copy.dx : copy.dy; };
    const int lines = int(copied.size());
    // Only the trust of wide runs is written, and only the shifts read.
    parallel_for(0, lines, [&](int64_t line) {
        for (CopiedRun& run : copied[size_t(line)]) {
            if (run.end - run.begin <= widest_lone_run || run.copy.trust <= 0.0f)
                continue;
            int asked = 0, agreeing = 0;
            for (int other = std::max(0, int(line) - neighbour_lines);
                 other <= std::min(lines - 1, int(line) + neighbour_lines); ++other) {
                if (other == int(line))
                    continue;
                bool crossed = false, same = false;
                for (const CopiedRun& beside : copied[size_t(other)])
                    if (beside.begin < run.end && beside.end > run.begin) {
                        crossed = true;
                        // A run beside without a copy has shift 0, which
                        // no copy has.
                        same = same || std::abs(shift(beside.copy) - shift(run.copy)) <= 1;
                    }
                asked += crossed;
                agreeing += same;
            }
            run.copy.trust *= asked > 0 ? float(agreeing) / float(asked) : 0.0f;
        }
    }, by_rows(nthreads));
}

const ContinuedPatterns::Copy*
ContinuedPatterns::copy_at(const std::vector<std::vector<CopiedRun>>& copied, int first_line,
                           int v, int u)
{
    const size_t line = size_t(v - first_line);
    if (v < first_line || line >= copied.size())
        return nullptr;
    const std::vector<CopiedRun>& runs = copied[line];
    auto after = std::upper_bound(runs.begin(), runs.end(), u,
                                  [](int at, const CopiedRun& run) { return at < run.begin; });
    if (after == runs.begin() || u >= std::prev(after)->end)
        return nullptr;
    return &std::prev(after)->copy;
}

bool ContinuedPatterns::at(int x, int y, float value[5], float& trust) const
{
    // The better of the copies along its row and its column.
    const Copy* along_row = copy_at(m_row_copies, m_window.ybegin, y, x);
    const Copy* along_column = copy_at(m_column_copies, m_window.xbegin, x, y);
    const Copy* copy = !along_column || (along_row && along_row->trust >= along_column->trust)
                           ? along_row
                           : along_column;
    if (!copy || copy->trust <= 0.0f)
        return false;
    observation(x + copy->dx, y + copy->dy, value);
    trust = copy->trust;
    return true;
}

}  // namespace defocus
