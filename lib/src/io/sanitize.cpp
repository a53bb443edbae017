#include <defocus/scene.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include <OpenImageIO/parallel.h>

#include "util/parallel_rows.h"

namespace defocus {

namespace {

const float infinity = std::numeric_limits<float>::infinity();
/// Depths from here on are a renderer's "no surface" (1e10 in most).
const float empty_depth = 1e9f;

/// Colour beyond this is clamped to it. Spreading sums light in float,
/// whose limit is 3.4e38: colour near that (finite, but no render's) made
/// the sums overflow into NaN. 1e30 leaves room for a sum of 3e8 pixels.
const float largest_color = 1e30f;

/// Applies the rules of sanitize() to one pixel or sample; counts into n.
/// Returns false when the pixel carries no light (and has been cleared).
bool sanitize_one(float& r, float& g, float& b, float& a, float& z, PixelCounts& n)
{
    const bool finite = std::isfinite(r) && std::isfinite(g) && std::isfinite(b)
                        && std::isfinite(a);
    if (!finite || a <= 0.0f) {
        if (!finite)
            ++n.nonfinite_color;
        else if (r != 0.0f || g != 0.0f || b != 0.0f)
            ++n.transparent_light;
        r = g = b = a = 0.0f;
        return false;
    }
    if (!(z > 0.0f)) {
        ++n.bad_depth;
        z = infinity;
    }
    // Coverage above 1 makes "over" amplify what lies behind: deep samples
    // of alpha 1e31 composited into inf and NaN (fuzz_scene).
    if (a > 1.0f) {
        ++n.alpha_above_one;
        a = 1.0f;
    }
    if (std::max({ std::abs(r), std::abs(g), std::abs(b) }) > largest_color) {
        ++n.huge_color;
        for (float* c : { &r, &g, &b })
            *c = std::clamp(*c, -largest_color, largest_color);
    }
    return true;
}

struct AtomicCounts {
    std::atomic<int64_t> nonfinite { 0 }, huge { 0 }, opaque { 0 }, depth { 0 },
        transparent { 0 }, edge { 0 };
    void add(const PixelCounts& n)
    {
        nonfinite += n.nonfinite_color;
        huge += n.huge_color;
        opaque += n.alpha_above_one;
        depth += n.bad_depth;
        transparent += n.transparent_light;
        edge += n.edge_depth;
    }
};

/// Gives antialiased edge pixels without a depth of their own the depth of
/// their most covered neighbour that has one (see sanitize()). Neighbours
/// are read before any pixel is changed, so the order does not matter.
void fill_edge_depth(Layer& layer, AtomicCounts& counts, int nthreads)
{
    const OIIO::ROI roi = layer.color.roi();
    const int w = roi.width(), h = roi.height();
    const float* color = static_cast<const float*>(layer.color.localpixels());
    float* depth = static_cast<float*>(layer.depth.localpixels());
    auto has_depth = [&](size_t p) { return color[p * 4 + 3] > 0.0f && depth[p] < empty_depth; };
    std::vector<std::vector<std::pair<size_t, float>>> rows(size_t(std::max(0, h)));
    OIIO::parallel_for(0, h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            const size_t p = size_t(y) * w + x;
            const float a = color[p * 4 + 3];
            if (!(a > 0.0f && a < 1.0f) || depth[p] < empty_depth)
                continue;
            float best_alpha = 0.0f, z = 0.0f;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nx = x + dx, ny = y + dy;
                    if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= w || ny >= h)
                        continue;
                    const size_t q = size_t(ny) * w + nx;
                    if (has_depth(q) && color[q * 4 + 3] > best_alpha) {
                        best_alpha = color[q * 4 + 3];
                        z = depth[q];
                    }
                }
            if (best_alpha > 0.0f)
                rows[y].emplace_back(p, z);
        }
    }, by_rows(nthreads));
    PixelCounts n;
    for (const auto& row : rows)
        for (const auto& [p, z] : row) {
            depth[p] = z;
            ++n.edge_depth;
        }
    counts.add(n);
}

void sanitize_layer(Layer& layer, AtomicCounts& counts, int nthreads)
{
    const OIIO::ROI roi = layer.color.roi();
    OIIO::parallel_for_chunked(roi.ybegin, roi.yend, 0, [&](int64_t y0, int64_t y1) {
        PixelCounts n;
        for (int64_t y = y0; y < y1; ++y) {
            float* c = static_cast<float*>(layer.color.pixeladdr(roi.xbegin, int(y)));
            float* z = static_cast<float*>(layer.depth.pixeladdr(roi.xbegin, int(y)));
            for (int x = 0; x < roi.width(); ++x, c += 4, ++z)
                sanitize_one(c[0], c[1], c[2], c[3], *z, n);
        }
        counts.add(n);
    }, by_rows(nthreads));
}

void sanitize_deep(DeepImage& image, AtomicCounts& counts, int nthreads)
{
    const int64_t npixels = int64_t(image.offsets.size()) - 1;
    OIIO::parallel_for_chunked(int64_t(0), npixels, 0, [&](int64_t p0, int64_t p1) {
        PixelCounts n;
        for (uint64_t i = image.offsets[p0]; i < image.offsets[p1]; ++i) {
            DeepSample& s = image.samples[i];
            if (sanitize_one(s.r, s.g, s.b, s.a, s.z, n) && !(s.zback >= s.z))
                s.zback = s.z;
        }
        counts.add(n);
    }, OIIO::paropt(nthreads));
}

}  // namespace

PixelCounts sanitize(Scene& scene, int nthreads)
{
    AtomicCounts counts;
    for_each_content(scene,
        [&](Layer& layer) {
            sanitize_layer(layer, counts, nthreads);
            fill_edge_depth(layer, counts, nthreads);
            return true;
        },
        [&](DeepImage& image) {
            sanitize_deep(image, counts, nthreads);
            return true;
        });
    return { counts.nonfinite, counts.huge,        counts.opaque,
             counts.depth,     counts.transparent, counts.edge };
}

}  // namespace defocus
