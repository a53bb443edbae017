#include <defocus/composite/coc_aov.h>

#include <algorithm>

#include <OpenImageIO/parallel.h>

#include "util/float_pixels.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// `layer` with each pixel's signed CoC diameter as its colour,
/// premultiplied: red holds it behind the focus, green in front (spread
/// colour stays non-negative).
Layer coc_layer(const Layer& layer, const CircleOfConfusion& coc, int nthreads)
{
    ImageSpec spec = layer.color.spec();
    spec.set_format(TypeFloat);
    Layer out { layer.name, ImageBuf(spec, InitializePixels::No), layer.depth, {} };
    const ROI roi = layer.color.roi();
    const FloatPixels color(layer.color, roi);
    const FloatPixels depth(layer.depth, ROI(roi.xbegin, roi.xend, roi.ybegin, roi.yend, 0, 1,
                                             0, 1));
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        float* o = static_cast<float*>(out.color.pixeladdr(roi.xbegin, y));
        for (int x = roi.xbegin; x < roi.xend; ++x, o += 4) {
            const float a = color(x, y)[3];
            const double c = coc.diameter(*depth(x, y), x, y);
            o[0] = float(a * std::max(c, 0.0));
            o[1] = float(a * std::max(-c, 0.0));
            o[2] = 0.0f;
            o[3] = a;
        }
    }, by_rows(nthreads));
    return out;
}

}  // namespace

bool coc_aov(ImageBuf& dst, const LayeredScene& scene, const Camera& camera,
             const SpreadOptions& spread, const ApertureImages& images, OutputWindow window,
             ROI roi, int nthreads)
{
    ImageSpec spec(roi.width(), roi.height(), 1, TypeFloat);
    spec.x = roi.xbegin;
    spec.y = roi.ybegin;
    spec.channelnames = { "coc" };
    dst.reset(spec, InitializePixels::Yes);
    const ReachOnly reach = reach_only(camera, spread, images);
    const CircleOfConfusion coc(reach.camera, scene.spec.roi_full());
    // Back to front: the front-most layer that reaches a pixel writes it last.
    for (size_t i = 0; i < scene.layers.size(); ++i) {
        if (scene.reports[i].pixels == 0)
            continue;
        LayeredScene alone;
        alone.source = scene.source;
        alone.spec = scene.spec;
        alone.luma = scene.luma;
        alone.layers.push_back(coc_layer(scene.layers[i], coc, nthreads));
        alone.reports = { scene.reports[i] };
        ImageBuf spread_layer;
        if (!defocus_layers(spread_layer, alone, reach.camera, reach.spread, reach.images,
                            window, nullptr, nullptr, nthreads)) {
            dst.errorfmt("{}", spread_layer.geterror());
            return false;
        }
        const ROI both = roi_intersection(roi, spread_layer.roi());
        parallel_for(both.ybegin, both.yend, [&](int y) {
            const float* s = static_cast<const float*>(spread_layer.pixeladdr(both.xbegin, y));
            float* out = static_cast<float*>(dst.pixeladdr(both.xbegin, y));
            for (int x = both.xbegin; x < both.xend; ++x, s += 4, ++out)
                if (s[3] > reach_coverage)
                    *out = (s[0] - s[1]) / s[3];
        }, by_rows(nthreads));
    }
    return true;
}

}  // namespace defocus
