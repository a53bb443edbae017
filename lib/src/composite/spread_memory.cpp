#include "composite/spread_memory.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <OpenImageIO/parallel.h>

#include <defocus/shot/memory_limit.h>

#include "composite/sub_aperture.h"

namespace defocus {

using namespace OIIO;

namespace {

/// How far a layer's light lands from its pixels, and a pixel more.
ROI grown_by_blur(const ROI& roi, const LayerReport& report)
{
    const int reach = int(std::ceil(0.5 * std::max(std::abs(report.coc_min),
                                                   std::abs(report.coc_max))))
                      + 1;
    ROI grown = roi;
    grown.xbegin -= reach;
    grown.xend += reach;
    grown.ybegin -= reach;
    grown.yend += reach;
    return grown;
}

/// What SubApertureLayers keeps while the layers are spread, as if every
/// tile took cells: each layer's change (half RGBA) over where its light
/// lands in `frame`.
double change_bytes(const LayeredScene& layered, const ROI& frame)
{
    double bytes = 0.0;
    for (size_t i = 0; i < layered.layers.size(); ++i)
        bytes += SubApertureLayers::change_bytes
                 * double(roi_intersection(
                              grown_by_blur(layered.layers[i].color.roi(), layered.reports[i]),
                              frame)
                              .npixels());
    return bytes;
}

/// What SubApertureLayers holds while it finds the changes, and frees
/// before the layers are spread: each layer as the cells read it (a float
/// RGBA copy unless it is one, and while it is made its radius, and its
/// runs, here 8 bytes a pixel), and again over blocks of 2 x 2 and 4 x 4
/// pixels (their colour, radius and runs); and on each of
/// `nthreads` threads, a window of tiles of `frame` with each layer's sums
/// (two float RGBA) and how it covers each pixel (a byte), the window's
/// light through a cell (double RGBA), transmittances (two doubles) and
/// where a layer is solid and the layers so far hide it (two bytes), and the
/// counts that find where a layer is solid (an int over the window grown
/// by the farthest blur).
double cell_work_bytes(const LayeredScene& layered, const ROI& frame, int nthreads)
{
    double bytes = 0.0;
    int reach = 0;
    for (size_t i = 0; i < layered.layers.size(); ++i) {
        const Layer& layer = layered.layers[i];
        const ROI roi = layer.color.roi();
        reach = std::max(reach, roi.xbegin - grown_by_blur(roi, layered.reports[i]).xbegin);
        const bool copied = layer.color.spec().format != TypeFloat || layer.color.nchannels() != 4;
        const double over_blocks = (1.0 / 4.0 + 1.0 / 16.0) * float_bytes(1.0, 4 + 1 + 2);
        bytes += double(roi.npixels())
                 * ((copied ? float_bytes(1.0, 4) : 0.0) + float_bytes(1.0, 2) + over_blocks);
    }
    const int columns = SubApertureLayers::window_columns * CellTiles::size,
              rows = SubApertureLayers::window_rows * CellTiles::size;
    const double width = std::min(frame.width(), columns) + 2,
                 height = std::min(frame.height(), rows) + 2;
    const double per_layer = 2.0 * float_bytes(1.0, 4) + 1.0;
    const double per_pixel = 4.0 * sizeof(double) + 2.0 * sizeof(double) + 2.0;
    const double counts = (width + 2.0 * reach) * (height + 2.0 * reach) * sizeof(int32_t);
    const int threads = nthreads > 0 ? nthreads : OIIO::get_int_attribute("threads", 1);
    return bytes
           + double(threads)
                 * (width * height * (per_layer * double(layered.layers.size()) + per_pixel)
                    + counts);
}

}  // namespace

double result_bytes(double pixels)
{
    return 2.0 * float_bytes(pixels, 4);
}

double spread_bytes(const LayeredScene& layered, const SpreadOptions& spread,
                    const Camera& camera, int nthreads)
{
    const DeepImage* holdout = layered.holdout.get();
    const double holdout_bytes = holdout ? double(holdout->samples.size() * sizeof(DeepSample)
                                                  + holdout->offsets.size() * sizeof(uint64_t))
                                         : 0.0;
    // The layers as held, and what spreading them adds.
    double layers = 0.0, spreading = 0.0;
    ROI all = layered.spec.roi();
    for (size_t i = 0; i < layered.layers.size(); ++i) {
        const Layer& layer = layered.layers[i];
        const ROI roi = layer.color.roi();
        const ROI grown = grown_by_blur(roi, layered.reports[i]);
        const double growth = roi.npixels() > 0 ? double(grown.npixels()) / roi.npixels() : 0.0;
        double held = 0.0;
        for (const ImageBuf* image : { &layer.color, &layer.depth, &layer.rebuilt })
            held += image->initialized() ? double(image->spec().image_bytes()) : 0.0;
        const double blur_field = float_bytes(1.0, 1) + 1.0;  // a radius and a mask byte
        layers += held;
        spreading += held * (growth - 1.0) + blur_field * double(grown.npixels());
        all = roi_union(all, grown);
    }
    spreading += result_bytes(double(all.npixels()));
    // The cells' changes are found before the layers are spread, and kept
    // while they are: green's, and under axial aberration red and blue's.
    if (!takes_aperture_cells(spread, layered))
        return holdout_bytes + layers + spreading;
    const double sets = camera.axial_ca != 0.0 ? 2.0 : 1.0;
    return holdout_bytes + layers + sets * change_bytes(layered, all)
           + std::max(spreading, cell_work_bytes(layered, all, nthreads));
}

}  // namespace defocus
