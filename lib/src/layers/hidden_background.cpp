// Filling the background a flat render cannot see (push-pull: Gortler,
// Grzeszczuk, Szeliski & Cohen, "The Lumigraph", SIGGRAPH 1996).
#include <defocus/layers/layering.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>

#include <OpenImageIO/parallel.h>

#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// One pyramid cell: sums over the observed pixels of premultiplied
/// R, G, B, A and of A·Z, and their count.
struct Cell {
    float v[5] = { 0, 0, 0, 0, 0 };
    float w = 0;
};

struct Level {
    int width, height;
    std::vector<Cell> cells;
    Cell& at(int x, int y) { return cells[size_t(y) * width + x]; }
    const Cell& at(int x, int y) const { return cells[size_t(y) * width + x]; }
};

float brightness(const float* rgba)
{
    return std::max(0.0f, (rgba[0] + rgba[1] + rgba[2]) / 3.0f);
}

/// The mean brightness of the layer's observed covered pixels, per unit
/// of coverage.
float mean_brightness(const Layer& layer, const std::vector<uint8_t>& holes, int nthreads)
{
    const ROI roi = layer.color.roi();
    // Per row, then added in order: the same sum on any number of threads.
    std::vector<double> light(roi.height(), 0.0), coverage(roi.height(), 0.0);
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        const int row = y - roi.ybegin;
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const float* c = static_cast<const float*>(layer.color.pixeladdr(x, y));
            if (!holes[size_t(row) * roi.width() + (x - roi.xbegin)] && c[3] > 0.0f) {
                light[row] += brightness(c);
                coverage[row] += c[3];
            }
        }
    }, by_rows(nthreads));
    const double all_light = std::accumulate(light.begin(), light.end(), 0.0);
    const double all_coverage = std::accumulate(coverage.begin(), coverage.end(), 0.0);
    return all_coverage > 0.0 ? float(all_light / all_coverage) : 1.0f;
}

/// Push-pull levels above the pixels for a fill up to `max_distance`:
/// as many as make a cell span it.
int pyramid_levels(double max_distance)
{
    return 1 + int(std::ceil(std::log2(std::max(2.0, max_distance))));
}

}  // namespace

ROI hidden_background_window(const ROI& content, const ROI& frame, double max_distance)
{
    // A hidden pixel is filled from the cells of each level next to its
    // own, so content reaches it from two of the coarsest cells away at
    // most, and what those cells sum lies within one more: beyond four
    // cells nothing changes a pixel that gets any coverage. The window
    // keeps the frame's grid of coarsest cells, so that every cell sums
    // the same pixels.
    const int64_t cell = int64_t(1) << std::min(pyramid_levels(max_distance), 30);
    auto grid_below = [&](int64_t v, int origin) {
        const int64_t steps = (v - origin) >= 0 ? (v - origin) / cell
                                                : -((origin - v + cell - 1) / cell);
        return origin + steps * cell;
    };
    const int64_t x0 = grid_below(int64_t(content.xbegin) - 4 * cell, frame.xbegin);
    const int64_t y0 = grid_below(int64_t(content.ybegin) - 4 * cell, frame.ybegin);
    const int64_t x1 = int64_t(content.xend) + 4 * cell, y1 = int64_t(content.yend) + 4 * cell;
    return ROI(int(std::max<int64_t>(x0, frame.xbegin)), int(std::min<int64_t>(x1, frame.xend)),
               int(std::max<int64_t>(y0, frame.ybegin)), int(std::min<int64_t>(y1, frame.yend)),
               0, 1, 0, 4);
}

void fill_hidden_background(Layer& layer, const std::vector<uint8_t>& holes,
                            double max_distance, int nthreads)
{
    const ROI roi = layer.color.roi();
    std::vector<Level> pyramid;
    pyramid.push_back({ roi.width(), roi.height(), {} });
    pyramid[0].cells.resize(roi.npixels());
    const float highlight = mean_brightness(layer, holes, nthreads);
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            // Every pixel not hidden is an observation of the layer, empty
            // ones too: the fill estimates coverage as well as colour.
            const size_t p = size_t(y - roi.ybegin) * roi.width() + (x - roi.xbegin);
            if (holes[p])
                continue;
            const float* c = static_cast<const float*>(layer.color.pixeladdr(x, y));
            Cell& cell = pyramid[0].cells[p];
            // A highlight weighs as much light as the layer's mean
            // brightness: what continues behind the nearer layer is not
            // known, and a small light beside the hole must not flood it
            // (the mean of a light 100 times brighter than a wall and of
            // seven wall pixels is 13 walls; weighted, it is 1.1).
            const float w = std::min(1.0f, highlight / std::max(brightness(c), 1e-30f));
            for (int i = 0; i < 4; ++i)
                cell.v[i] = w * c[i];
            const float z = *static_cast<const float*>(layer.depth.pixeladdr(x, y));
            cell.v[4] = c[3] > 0.0f ? w * c[3] * std::min(z, 1e30f) : 0.0f;
            cell.w = w;
        }
    }, by_rows(nthreads));

    // Push: each level sums 2x2 cells of the finer one, as far as a cell
    // spans the distance to fill.
    const int levels = pyramid_levels(max_distance);
    for (int l = 1; l <= levels && (pyramid.back().width > 1 || pyramid.back().height > 1); ++l) {
        const Level& fine = pyramid.back();
        Level coarse { (fine.width + 1) / 2, (fine.height + 1) / 2, {} };
        coarse.cells.resize(size_t(coarse.width) * coarse.height);
        parallel_for(0, coarse.height, [&](int y) {
            for (int x = 0; x < coarse.width; ++x) {
                Cell& c = coarse.at(x, y);
                for (int fy = 2 * y; fy < std::min(2 * y + 2, fine.height); ++fy)
                    for (int fx = 2 * x; fx < std::min(2 * x + 2, fine.width); ++fx) {
                        const Cell& f = fine.at(fx, fy);
                        for (int i = 0; i < 5; ++i)
                            c.v[i] += f.v[i];
                        c.w += f.w;
                    }
            }
        }, by_rows(nthreads));
        pyramid.push_back(std::move(coarse));
    }
    // Pull: an empty cell takes the coarser level's averages, interpolated
    // bilinearly between the four nearest coarse cells that have any.
    for (int l = int(pyramid.size()) - 2; l >= 0; --l) {
        Level& fine = pyramid[l];
        const Level& coarse = pyramid[l + 1];
        parallel_for(0, fine.height, [&](int y) {
            for (int x = 0; x < fine.width; ++x) {
                Cell& f = fine.at(x, y);
                if (f.w > 0.0f)
                    continue;
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
                    continue;
                for (int k = 0; k < 5; ++k)
                    f.v[k] = sum[k] / weight;
                f.w = 1.0f;
            }
        }, by_rows(nthreads));
    }

    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t p = size_t(y - roi.ybegin) * roi.width() + (x - roi.xbegin);
            const Cell& cell = pyramid[0].cells[p];
            if (!holes[p] || cell.w <= 0.0f)
                continue;
            if (cell.v[3] <= 0.0f)
                continue;
            float* c = static_cast<float*>(layer.color.pixeladdr(x, y));
            for (int i = 0; i < 4; ++i)
                c[i] = cell.v[i] / cell.w;
            *static_cast<float*>(layer.depth.pixeladdr(x, y)) = cell.v[4] / cell.v[3];
        }
    }, by_rows(nthreads));
}

}  // namespace defocus
