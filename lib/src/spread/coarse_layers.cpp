#include "spread/coarse_layers.h"

#include <algorithm>
#include <cmath>

#include "spread/block_levels.h"
#include "util/parallel_rows.h"

namespace defocus {

using OIIO::ROI;

namespace {

/// The blocks of `scale` pixels from `origin` that [begin, end) meets.
void blocks(int begin, int end, int scale, int origin, int& first, int& last_end)
{
    first = floor_div(begin - origin, scale);
    last_end = floor_div(end - 1 - origin, scale) + 1;
}

}  // namespace

ROI blocks_of(const ROI& pixels, int scale, int x0, int y0)
{
    int x[2], y[2];
    blocks(pixels.xbegin, pixels.xend, scale, x0, x[0], x[1]);
    blocks(pixels.ybegin, pixels.yend, scale, y0, y[0], y[1]);
    return ROI(x[0], x[1], y[0], y[1]);
}

SignedLayer coarse_layer(const SignedLayer& fine, const ROI& within, int scale, int x0, int y0,
                         std::vector<float>& color, int nthreads)
{
    SignedLayer coarse;
    const ROI pixels = OIIO::roi_intersection(fine.roi, within);
    if (!fine.color || !has_pixels(pixels))
        return coarse;
    ROI roi = blocks_of(pixels, scale, x0, y0);
    roi.chbegin = 0;
    roi.chend = 4;
    const int width = roi.width(), fine_width = fine.roi.width();
    color.assign(size_t(width) * roi.height() * 4, 0.0f);
    std::vector<float> radius(size_t(width) * roi.height(), 0.0f);
    const float area = 1.0f / float(scale * scale);
    const int left = x0 + roi.xbegin * scale, right = x0 + roi.xend * scale;
    parallel_for_each_item(0, roi.height(), [&](int64_t row) {
        float* rgba = &color[size_t(row) * width * 4];
        float* r = &radius[size_t(row) * width];
        std::vector<float> coverage(size_t(width), 0.0f);
        const int top = y0 + (roi.ybegin + int(row)) * scale;
        for (int y = std::max(top, fine.roi.ybegin); y < std::min(top + scale, fine.roi.yend);
             ++y) {
            const size_t fine_row = size_t(y - fine.roi.ybegin);
            const float* pixels = fine.color + fine_row * fine_width * 4;
            for (size_t k = fine.row_runs[fine_row]; k < fine.row_runs[fine_row + 1]; ++k) {
                const PixelRun& run = fine.runs[k];
                for (int x = std::max(run.x_begin, left); x < std::min(run.x_end, right); ++x) {
                    const int block = floor_div(x - x0, scale) - roi.xbegin;
                    const float* p = pixels + size_t(x - fine.roi.xbegin) * 4;
                    for (int c = 0; c < 4; ++c)
                        rgba[block * 4 + c] += p[c] * area;
                    // Lit pixels without coverage (emission) still count.
                    const float weight = std::max(p[3], 1e-6f);
                    r[block] += weight * run.radius;
                    coverage[size_t(block)] += weight;
                }
            }
        }
        for (int i = 0; i < width; ++i)
            r[i] = coverage[size_t(i)] > 0.0f ? r[i] / coverage[size_t(i)] / float(scale) : 0.0f;
    }, nthreads);
    coarse.set(roi, color.data(), radius.data(), fine.extent, nthreads);
    return coarse;
}

RadiusTiles::RadiusTiles(const SignedLayer& layer, int size, int x0, int y0)
    : m_size(size)
    , m_x0(x0)
    , m_y0(y0)
{
    if (!layer.lit.defined())
        return;
    m_tiles = blocks_of(layer.lit, size, x0, y0);
    const size_t n = size_t(m_tiles.width()) * m_tiles.height();
    m_least.assign(n, INFINITY);
    m_most.assign(n, -INFINITY);
    for (int y = layer.lit.ybegin; y < layer.lit.yend; ++y) {
        const size_t row = size_t(y - layer.roi.ybegin);
        const int tile_row = floor_div(y - y0, size) - m_tiles.ybegin;
        for (size_t k = layer.row_runs[row]; k < layer.row_runs[row + 1]; ++k) {
            const PixelRun& run = layer.runs[k];
            const float r = std::abs(run.radius);
            const int last = floor_div(run.x_end - 1 - x0, size);
            for (int t = floor_div(run.x_begin - x0, size); t <= last; ++t) {
                const size_t i = size_t(tile_row) * m_tiles.width() + size_t(t - m_tiles.xbegin);
                m_least[i] = std::min(m_least[i], r);
                m_most[i] = std::max(m_most[i], r);
            }
        }
    }
}

bool RadiusTiles::range(const ROI& roi, float& least, float& most) const
{
    least = INFINITY;
    most = -INFINITY;
    if (m_least.empty())  // nothing lit; m_tiles is undefined, which OIIO takes as all
        return false;
    const ROI tiles = OIIO::roi_intersection(blocks_of(roi, m_size, m_x0, m_y0), m_tiles);
    for (int y = tiles.ybegin; y < tiles.yend; ++y)
        for (int x = tiles.xbegin; x < tiles.xend; ++x) {
            const size_t i = size_t(y - m_tiles.ybegin) * m_tiles.width()
                             + size_t(x - m_tiles.xbegin);
            least = std::min(least, m_least[i]);
            most = std::max(most, m_most[i]);
        }
    return most >= least;
}

int coarsest_scale(const std::vector<SignedLayer>& layers, const std::vector<RadiusTiles>& radii,
                   const ROI& window, double cell_width)
{
    int scale = 4;
    for (size_t l = 0; l < layers.size() && scale > 1; ++l) {
        const SignedLayer& layer = layers[l];
        if (!has_pixels(layer.light_in(window)))
            continue;
        float least, most;
        if (!radii[l].range(layer.sources_of(window), least, most) || most < sharp_radius)
            continue;
        const double blur = least * cell_width;
        while (scale > 1 && blur < 3.0 * scale)
            scale /= 2;
    }
    return scale;
}

}  // namespace defocus
