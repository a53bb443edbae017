#include <defocus/layers/layered_scene.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/parallel.h>

#include "util/bounding_box.h"
#include "util/float_pixels.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// Per-row partial sums of describe_layer(), reduced after the parallel pass.
struct RowDepth {
    int64_t pixels = 0;
    double zmin = INFINITY, zmax = -INFINITY;
    double cmin = INFINITY, cmax = -INFINITY;
    double weight = 0, weighted_inverse = 0;

    void add_coc(const CircleOfConfusion& coc, double z, int x, int y)
    {
        const double c = coc.diameter(z, x, y);
        cmin = std::min(cmin, c);
        cmax = std::max(cmax, c);
        if (coc.per_channel()) {  // red and blue reach further on one side
            const double rb = coc.diameter(z, x, y, CocChannel::RedBlue);
            cmin = std::min(cmin, rb);
            cmax = std::max(cmax, rb);
        }
    }
};

}  // namespace

LayerReport describe_layer(const Layer& layer, const CircleOfConfusion& coc, int nthreads)
{
    const ROI roi = layer.color.roi();
    const FloatPixels color(layer.color, roi);
    const FloatPixels depth(layer.depth, ROI(roi.xbegin, roi.xend, roi.ybegin, roi.yend, 0, 1, 0, 1));
    std::vector<RowDepth> rows(roi.height());
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        RowDepth& r = rows[y - roi.ybegin];
        const float* c = color(roi.xbegin, y);
        const float* zs = depth(roi.xbegin, y);
        for (int x = 0; x < roi.width(); ++x, c += color.nchannels(), zs += depth.nchannels()) {
            const float a = c[3];
            if (a <= 0.0f)
                continue;
            const double z = *zs;
            ++r.pixels;
            r.zmin = std::min(r.zmin, z);
            r.zmax = std::max(r.zmax, z);
            // The CoC per pixel is the spread's to compute; here only
            // where the depth alone does not say it.
            if (coc.varies_over_frame())
                r.add_coc(coc, z, roi.xbegin + x, y);
            r.weight += a;
            r.weighted_inverse += a * (std::isinf(z) ? 0.0 : 1.0 / z);
        }
    }, by_rows(nthreads));
    RowDepth total;
    for (const RowDepth& r : rows) {
        total.pixels += r.pixels;
        total.zmin = std::min(total.zmin, r.zmin);
        total.zmax = std::max(total.zmax, r.zmax);
        total.cmin = std::min(total.cmin, r.cmin);
        total.cmax = std::max(total.cmax, r.cmax);
        total.weight += r.weight;
        total.weighted_inverse += r.weighted_inverse;
    }
    if (!coc.varies_over_frame() && total.pixels) {
        total.add_coc(coc, total.zmin, roi.xbegin, roi.ybegin);
        total.add_coc(coc, total.zmax, roi.xbegin, roi.ybegin);
    }
    LayerReport rep;
    rep.mean_inverse_depth = total.weight > 0 ? total.weighted_inverse / total.weight : 0.0;
    rep.name = layer.name;
    rep.pixels = total.pixels;
    rep.depth_min = total.pixels ? total.zmin : 0.0;
    rep.depth_max = total.pixels ? total.zmax : 0.0;
    rep.coc_min = total.pixels ? total.cmin : 0.0;
    rep.coc_max = total.pixels ? total.cmax : 0.0;
    return rep;
}

std::vector<size_t> lit_layers(const LayeredScene& scene)
{
    std::vector<size_t> lit;
    for (size_t i = 0; i < scene.layers.size(); ++i)
        if (scene.reports[i].pixels > 0)
            lit.push_back(i);
    return lit;
}

OIIO::ImageSpec display_picture_spec(const LayeredScene& scene)
{
    const OIIO::ImageSpec& s = scene.spec;
    OIIO::ImageSpec spec(s.full_width, s.full_height, 4, OIIO::TypeFloat);
    spec.x = spec.full_x = s.full_x;
    spec.y = spec.full_y = s.full_y;
    spec.channelnames = { "R", "G", "B", "A" };
    spec.alpha_channel = 3;
    return spec;
}

void crop_to_content(Layer& layer, int nthreads)
{
    const ROI roi = layer.color.roi();
    const FloatPixels pixels(layer.color, roi);
    ROI content = bounding_box(roi, [&](int x, int y) {
        const float* c = pixels(x, y);
        return c[0] != 0.0f || c[1] != 0.0f || c[2] != 0.0f || c[3] != 0.0f;
    }, nthreads);
    if (content.width() == 0)
        content = ROI(roi.xbegin, roi.xbegin, roi.ybegin, roi.ybegin, 0, 1, 0, 4);
    if (content == roi)
        return;
    ImageBuf color, depth, rebuilt;
    ImageBufAlgo::crop(color, layer.color, content, nthreads);
    ROI zroi = content;
    zroi.chend = 1;
    ImageBufAlgo::crop(depth, layer.depth, zroi, nthreads);
    if (layer.rebuilt.initialized()) {
        const ROI kept = roi_intersection(layer.rebuilt.roi(), zroi);
        if (kept.npixels() > 0)
            ImageBufAlgo::crop(rebuilt, layer.rebuilt, kept, nthreads);
    }
    layer.color = std::move(color);
    layer.depth = std::move(depth);
    layer.rebuilt = std::move(rebuilt);
}

void order_layers(LayeredScene& scene, const CircleOfConfusion& coc, int nthreads)
{
    scene.reports.clear();
    for (const Layer& layer : scene.layers)
        scene.reports.push_back(describe_layer(layer, coc, nthreads));
    sort_back_to_front(scene);
}

void sort_back_to_front(LayeredScene& scene)
{
    std::vector<size_t> order(scene.layers.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        return scene.reports[a].mean_inverse_depth < scene.reports[b].mean_inverse_depth;
    });
    // Reserved: ImageBuf's move may throw, so a vector that grows copies.
    std::vector<Layer> layers;
    std::vector<LayerReport> reports;
    layers.reserve(order.size());
    reports.reserve(order.size());
    for (size_t i : order) {
        layers.push_back(std::move(scene.layers[i]));
        reports.push_back(scene.reports[i]);
    }
    scene.layers = std::move(layers);
    scene.reports = std::move(reports);
}

}  // namespace defocus
