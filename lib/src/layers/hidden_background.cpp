// Filling the background a flat render cannot see: structure continued
// along lines across thin holes (continued_lines.h), patterns copied across
// holes (continued_patterns.h), cut lights continued as discs
// (continued_lights.h), over push-pull
// (Gortler, Grzeszczuk, Szeliski & Cohen, "The Lumigraph", SIGGRAPH 1996).
#include <defocus/layers/layering.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>

#include <OpenImageIO/parallel.h>

#include "layers/brightness.h"
#include "layers/continued_lights.h"
#include "layers/continued_lines.h"
#include "layers/continued_patterns.h"
#include "layers/hole_map.h"
#include "util/bounding_box.h"
#include "util/float_pixels.h"
#include "util/fresh_array.h"
#include "util/fresh_image.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// One pyramid cell: sums over the observed pixels of premultiplied
/// R, G, B, A and of A·Z, and their count.
struct Cell {
    float v[5];
    float w;

    void add(const Cell& c)
    {
        for (int i = 0; i < 5; ++i)
            v[i] += c.v[i];
        w += c.w;
    }
};

/// A pyramid level, width x height cells, every one written where it is
/// made.
struct Level {
    int width, height;
    std::unique_ptr<Cell[]> cells;

    Level(int width, int height, int nthreads)
        : width(width)
        , height(height)
        , cells(fresh_array<Cell>(size_t(width) * height, nthreads))
    {
    }
    Cell& at(int x, int y) { return cells[size_t(y) * width + x]; }
    const Cell& at(int x, int y) const { return cells[size_t(y) * width + x]; }
};

/// The finer level's 2x2 cells, summed.
Level coarser(const Level& fine, int nthreads)
{
    Level coarse((fine.width + 1) / 2, (fine.height + 1) / 2, nthreads);
    parallel_for(0, coarse.height, [&](int y) {
        for (int x = 0; x < coarse.width; ++x) {
            Cell& c = coarse.at(x, y);
            c = Cell {};
            for (int fy = 2 * y; fy < std::min(2 * y + 2, fine.height); ++fy)
                for (int fx = 2 * x; fx < std::min(2 * x + 2, fine.width); ++fx)
                    c.add(fine.at(fx, fy));
        }
    }, by_rows(nthreads));
    return coarse;
}

/// The mean of the cells of `coarse` around the centre of fine cell (x, y),
/// interpolated bilinearly between the four nearest that have any; false
/// when none has.
bool pull(const Level& coarse, int x, int y, float mean[5])
{
    // Fine cell centre in coarse cell units.
    const float cx = 0.5f * (x + 0.5f) - 0.5f, cy = 0.5f * (y + 0.5f) - 0.5f;
    const int x0 = int(std::floor(cx)), y0 = int(std::floor(cy));
    const float fx = cx - x0, fy = cy - y0;
    float sum[5] = { 0, 0, 0, 0, 0 }, weight = 0.0f;
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
            const int u = std::clamp(x0 + i, 0, coarse.width - 1);
            const int v = std::clamp(y0 + j, 0, coarse.height - 1);
            const Cell& c = coarse.at(u, v);
            if (c.w <= 0.0f)
                continue;
            const float b = (i ? fx : 1 - fx) * (j ? fy : 1 - fy);
            for (int k = 0; k < 5; ++k)
                sum[k] += b * c.v[k] / c.w;
            weight += b;
        }
    if (weight <= 0.0f)
        return false;
    for (int k = 0; k < 5; ++k)
        mean[k] = sum[k] / weight;
    return true;
}

/// Push-pull levels above the pixels for a fill up to `max_distance`:
/// as many as make a cell span it.
int pyramid_levels(double max_distance)
{
    return 1 + int(std::ceil(std::log2(std::max(2.0, max_distance))));
}

/// The longest line along which structure is continued across a hole.
/// A hidden pixel shows through the nearer layer's blurred edge from up to
/// its blur radius inside the hole, and spreads its own light out over its
/// own radius; max_distance bounds each, so a hole up to twice their sum
/// wide matters all across. Longer lines join unrelated surfaces, and a
/// smooth fill does better there.
int line_length(double max_distance)
{
    return int(std::min(4.0 * max_distance, 65535.0));
}

/// How many times brighter than the layer's seen mean a small patch is to
/// be a light, which is continued behind what cuts it.
constexpr float light_brightness = 4.0f;

/// The widest run of a hole that a pattern is copied across (a card before
/// a checker wall): beyond it, a copy from along the same row joins
/// unrelated surfaces. Runs wider than ContinuedPatterns' lone runs are
/// copied only as far as the lines beside them agree. Not bound by the
/// lines' length: a line interpolates between its ends, a copy is checked
/// against its sides, and a run is copied whole or not at all, so its
/// pixels near the sides, which the lens sees, need the whole run.
constexpr int widest_pattern_run = 128;

/// The first pyramid level over `window`: per cell of 2x2 pixels, the sums
/// over its observed pixels (those not in `holes`), each weighed so that it counts as no brighter than
/// `highlight`.
Level observed_cells(const FloatPixels& color, const FloatPixels& depth,
                     const HoleMap& holes, const ROI& window, float highlight,
                     int nthreads)
{
    Level first((window.width() + 1) / 2, (window.height() + 1) / 2, nthreads);
    parallel_for(0, first.height, [&](int y) {
        for (int x = 0; x < first.width; ++x) {
            Cell& cell = first.at(x, y);
            cell = Cell {};
            const int x0 = window.xbegin + 2 * x, y0 = window.ybegin + 2 * y;
            for (int py = y0; py < std::min(y0 + 2, window.yend); ++py)
                for (int px = x0; px < std::min(x0 + 2, window.xend); ++px) {
                    // Every pixel not hidden is an observation of the layer,
                    // empty ones too: the fill estimates coverage as well as
                    // colour.
                    if (holes(px, py))
                        continue;
                    const float* c = color(px, py);
                    // A highlight weighs as much light as the layer's mean
                    // brightness: what continues behind the nearer layer is
                    // not known, and a small light beside the hole must not
                    // flood it (the mean of a light 100 times brighter than
                    // a wall and of seven wall pixels is 13 walls; weighted,
                    // it is 1.1).
                    const float w = std::min(1.0f, highlight / std::max(brightness(c), 1e-30f));
                    const float z = *depth(px, py);
                    for (int i = 0; i < 4; ++i)
                        cell.v[i] += w * c[i];
                    cell.v[4] += c[3] > 0.0f ? w * c[3] * std::min(z, 1e30f) : 0.0f;
                    cell.w += w;
                }
        }
    }, by_rows(nthreads));
    return first;
}

/// The push-pull pyramid up to `levels` levels above the pixels, from its
/// first level: every cell that sums nothing takes the coarser level's
/// averages.
std::vector<Level> push_pull(Level first, int levels, int nthreads)
{
    std::vector<Level> pyramid;
    pyramid.push_back(std::move(first));
    // Push: each level sums 2x2 cells of the finer one, as far as a cell
    // spans the distance to fill.
    for (int l = 2; l <= levels && (pyramid.back().width > 1 || pyramid.back().height > 1); ++l)
        pyramid.push_back(coarser(pyramid.back(), nthreads));
    // Pull: an empty cell takes the coarser level's averages.
    for (int l = int(pyramid.size()) - 2; l >= 0; --l) {
        Level& fine = pyramid[l];
        const Level& coarse = pyramid[l + 1];
        parallel_for(0, fine.height, [&](int y) {
            for (int x = 0; x < fine.width; ++x) {
                Cell& f = fine.at(x, y);
                if (f.w <= 0.0f && pull(coarse, x, y, f.v))
                    f.w = 1.0f;
            }
        }, by_rows(nthreads));
    }
    return pyramid;
}

}  // namespace

ROI hidden_background_window(const ROI& content, const ROI& frame, double max_distance)
{
    // A hidden pixel is filled from the cells of each level next to its
    // own, so content reaches it from two of the coarsest cells away at
    // most, and what those cells sum lies within one more: beyond four
    // cells nothing changes a pixel that gets any coverage. A line reaches
    // a pixel from content up to its length away, and reads around it as
    // far again. The window
    // keeps the frame's grid of coarsest cells, so that every cell sums
    // the same pixels.
    const int64_t cell = int64_t(1) << std::min(pyramid_levels(max_distance), 30);
    auto grid_below = [&](int64_t v, int origin) {
        const int64_t steps = (v - origin) >= 0 ? (v - origin) / cell
                                                : -((origin - v + cell - 1) / cell);
        return origin + steps * cell;
    };
    const int length = line_length(max_distance);
    const int64_t margin = std::max(4 * cell, int64_t(length) + ContinuedLines::reach(length));
    const int64_t x0 = grid_below(int64_t(content.xbegin) - margin, frame.xbegin);
    const int64_t y0 = grid_below(int64_t(content.ybegin) - margin, frame.ybegin);
    const int64_t x1 = int64_t(content.xend) + margin, y1 = int64_t(content.yend) + margin;
    return ROI(int(std::max<int64_t>(x0, frame.xbegin)), int(std::min<int64_t>(x1, frame.xend)),
               int(std::max<int64_t>(y0, frame.ybegin)), int(std::min<int64_t>(y1, frame.yend)),
               0, 1, 0, 4);
}

namespace {

/// The hidden pixels of `layer` within `window`, those of holes within
/// `hidden`, filled and marked in layer.rebuilt; counted into `rebuilt`.
void fill_holes(Layer& layer, const HoleMap& holes, const ROI& hidden, const ROI& window,
                float seen_brightness, double max_distance, RebuiltPixels& rebuilt,
                int nthreads)
{
    const ROI roi = layer.color.roi();
    const FloatPixels color(layer.color, roi);
    const FloatPixels depth(layer.depth, ROI(roi.xbegin, roi.xend, roi.ybegin, roi.yend, 0, 1, 0, 1));
    // The pyramid starts at 2x2 pixels a cell: the pixels themselves are
    // read where they are, and only the hidden ones are written.
    const std::vector<Level> pyramid = push_pull(
        observed_cells(color, depth, holes, window, seen_brightness, nthreads),
        pyramid_levels(max_distance), nthreads);

    // Lines and copies start at hidden pixels and read as far as their reach.
    auto reaching = [&](int reach) {
        return roi_intersection(ROI(hidden.xbegin - reach, hidden.xend + reach,
                                    hidden.ybegin - reach, hidden.yend + reach),
                                window);
    };
    const int length = line_length(max_distance);
    const ContinuedLines lines(color, depth, holes, reaching(ContinuedLines::reach(length)),
                               length, nthreads);
    const ContinuedPatterns patterns(color, depth, holes,
                                     reaching(ContinuedPatterns::reach(widest_pattern_run)),
                                     widest_pattern_run, nthreads);
    const ContinuedLights lights(color, depth, holes, window, light_brightness * seen_brightness,
                                 nthreads);

    std::vector<RebuiltPixels> rows(size_t(window.height()));
    parallel_for(window.ybegin, window.yend, [&](int y) {
        RebuiltPixels& counts = rows[size_t(y - window.ybegin)];
        // Row y's pixels from the window's first column on.
        const uint8_t* const flags = holes.row(window.xbegin, y);
        float* const color_row = static_cast<float*>(layer.color.pixeladdr(window.xbegin, y));
        float* const depth_row = static_cast<float*>(layer.depth.pixeladdr(window.xbegin, y));
        uint8_t* const rebuilt_row = static_cast<uint8_t*>(layer.rebuilt.pixeladdr(window.xbegin, y));
        for (int i = 0; i < window.width(); ++i) {
            if (flags[i] != HiddenPixels::hidden)
                continue;
            const int x = window.xbegin + i;
            // The smooth fill, then each estimate of structure blended in
            // as far as it is trusted (all of it where nothing came before);
            // `weight` keeps each one's share.
            float mean[5], estimate[5], trust = 0.0f;
            bool found = pull(pyramid[0], i, y - window.ybegin, mean);
            // In RebuiltBy's order from Smooth: smooth, lines, patterns,
            // continued (a cut light).
            float weight[4] = { found ? 1.0f : 0.0f, 0.0f, 0.0f, 0.0f };
            auto blend = [&](int method) {
                if (!found)
                    trust = 1.0f;
                for (int c = 0; c < 5; ++c)
                    mean[c] = trust * estimate[c] + (1 - trust) * (found ? mean[c] : 0.0f);
                for (float& w : weight)
                    w *= 1 - trust;
                weight[method] += trust;
                found = true;
            };
            if (lines.at(x, y, estimate, trust))
                blend(1);
            if (patterns.at(x, y, estimate, trust))
                blend(2);
            if (lights.at(x, y, estimate)) {
                trust = 1.0f;
                blend(3);
            }
            if (!found || mean[3] <= 0.0f)
                continue;
            std::copy(mean, mean + 4, color_row + 4 * size_t(i));
            depth_row[i] = mean[4] / mean[3];
            const RebuiltBy by = RebuiltBy(int(RebuiltBy::Smooth)
                                           + (std::max_element(weight, weight + 4) - weight));
            rebuilt_row[i] = uint8_t(by);
            counts.add(by);
        }
    }, by_rows(nthreads));
    for (const RebuiltPixels& row : rows)
        rebuilt.add(row);
}

}  // namespace

RebuiltPixels fill_hidden_background(Layer& layer, const HiddenPixels& hidden_pixels,
                                     double max_distance, int nthreads)
{
    RebuiltPixels rebuilt;
    const ROI roi = layer.color.roi();
    const HoleMap holes(hidden_pixels.flags, roi);
    // Only the pixels around the holes matter, as far as the fill reaches.
    const ROI hidden = bounding_box(roi, holes, nthreads);
    const ROI& continued = hidden_pixels.continued_box;
    if (hidden.width() == 0 && continued.width() == 0)
        return rebuilt;
    const ROI window = hidden.width() > 0 ? hidden_background_window(hidden, roi, max_distance)
                                          : continued;

    ImageSpec rebuilt_spec(continued.width() > 0 ? roi_union(window, continued) : window,
                           TypeUInt8);
    rebuilt_spec.nchannels = 1;
    rebuilt_spec.channelnames = { "rebuilt" };
    reset_zeroed_except(layer.rebuilt, rebuilt_spec, ROI(), nthreads);
    if (hidden.width() > 0)
        fill_holes(layer, holes, hidden, window, hidden_pixels.seen_brightness, max_distance,
                   rebuilt, nthreads);
    // A surface continued behind a nearer one's edge is made up as much as
    // a filled one.
    if (continued.width() > 0) {
        std::vector<int64_t> rows(size_t(continued.height()), 0);
        parallel_for(continued.ybegin, continued.yend, [&](int y) {
            const uint8_t* const flags = holes.row(continued.xbegin, y);
            uint8_t* const rebuilt_row
                = static_cast<uint8_t*>(layer.rebuilt.pixeladdr(continued.xbegin, y));
            for (int i = 0; i < continued.width(); ++i)
                if (flags[i] == HiddenPixels::continued) {
                    rebuilt_row[i] = uint8_t(RebuiltBy::Continued);
                    ++rows[size_t(y - continued.ybegin)];
                }
        }, by_rows(nthreads));
        for (int64_t n : rows)
            rebuilt.continued += n;
    }
    return rebuilt;
}

}  // namespace defocus
