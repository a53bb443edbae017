#include "composite/spread_memory.h"

#include <algorithm>
#include <cmath>

#include <defocus/shot/memory_limit.h>

namespace defocus {

using namespace OIIO;

double result_bytes(double pixels)
{
    return 2.0 * float_bytes(pixels, 4);
}

double spread_bytes(const LayeredScene& layered)
{
    const DeepImage* holdout = layered.holdout.get();
    double bytes = holdout ? double(holdout->samples.size() * sizeof(DeepSample)
                                    + holdout->offsets.size() * sizeof(uint64_t))
                           : 0.0;
    ROI all = layered.spec.roi();
    for (size_t i = 0; i < layered.layers.size(); ++i) {
        const Layer& layer = layered.layers[i];
        const LayerReport& r = layered.reports[i];
        const int reach =
            int(std::ceil(0.5 * std::max(std::abs(r.coc_min), std::abs(r.coc_max)))) + 1;
        const ROI roi = layer.color.roi();
        ROI grown = roi;
        grown.xbegin -= reach;
        grown.xend += reach;
        grown.ybegin -= reach;
        grown.yend += reach;
        const double growth = roi.npixels() > 0 ? double(grown.npixels()) / roi.npixels() : 0.0;
        double held = 0.0;
        for (const ImageBuf* image : { &layer.color, &layer.depth, &layer.rebuilt })
            held += image->initialized() ? double(image->spec().image_bytes()) : 0.0;
        const double blur_field = float_bytes(1.0, 1) + 1.0;  // a radius and a mask byte
        bytes += held * growth + blur_field * double(grown.npixels());
        all = roi_union(all, grown);
    }
    return bytes + result_bytes(double(all.npixels()));
}

}  // namespace defocus
