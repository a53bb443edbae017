#include "composite/data_spreads.h"

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/parallel.h>

#include "util/float_pixels.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

Layer quantity_layer(const Layer& layer, const ROI& roi, const QuantityFill& fill, int nthreads)
{
    ImageSpec spec = layer.color.spec();
    spec.set_roi(roi);
    spec.set_format(TypeFloat);
    Layer out { layer.name, ImageBuf(spec, InitializePixels::No), ImageBuf(), {} };
    ROI zroi = roi;
    zroi.chbegin = 0;
    zroi.chend = 1;
    const ROI whole = layer.depth.roi();
    if (whole == zroi && layer.depth.localpixels() && layer.depth.spec().format == TypeFloat)
        // The whole layer: its depth is read, not copied (the layer outlives
        // the spread).
        out.depth = ImageBuf(layer.depth.spec(), const_cast<void*>(layer.depth.localpixels()));
    else
        ImageBufAlgo::crop(out.depth, layer.depth, zroi, nthreads);
    const FloatPixels color(layer.color, roi);
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        float* o = static_cast<float*>(out.color.pixeladdr(roi.xbegin, y));
        for (int x = roi.xbegin; x < roi.xend; ++x, o += 4) {
            const float a = color(x, y)[3];
            float q[per_spread] = { 0.0f, 0.0f, 0.0f };
            if (a > 0.0f)
                fill(x, y, q);
            o[0] = q[0] * a;
            o[1] = q[1] * a;
            o[2] = q[2] * a;
            o[3] = a;
        }
    }, by_rows(nthreads));
    return out;
}

bool Spreader::spread(std::vector<Layer>&& layers, const std::vector<size_t>& from,
                      const QuantitySink& sink, std::string& error, bool own_light)
{
    if (keep_going && !keep_going(done++, total)) {
        error = "cancelled";
        return false;
    }
    LayeredScene alone;
    alone.source = scene.source;
    alone.spec = scene.spec;
    alone.luma = scene.luma;
    const CircleOfConfusion coc(reach.camera, scene.spec.roi_full());
    // ImageBuf's move may throw: a vector that grows copies its layers.
    alone.layers.reserve(layers.size());
    for (size_t k = 0; k < layers.size(); ++k) {
        // A whole layer's quantities have its alpha and depth: its report.
        const bool whole = layers[k].color.roi() == scene.layers[from[k]].color.roi();
        alone.reports.push_back(whole ? scene.reports[from[k]]
                                      : describe_layer(layers[k], coc, nthreads));
        alone.layers.push_back(std::move(layers[k]));
    }
    SpreadOptions options = reach.spread;
    if (own_light)
        options.aperture_cells = 1;
    return spread_layers_apart(alone, reach.camera, options, reach.images, window,
                               [&](size_t i, const ImageBuf& s, const ROI&) {
                                   sink(from[i], s);
                                   return true;
                               },
                               error, nullptr, nullptr, nthreads);
}

}  // namespace defocus
