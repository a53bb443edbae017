#include "spread_common.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

#include <OpenImageIO/parallel.h>

namespace defocus {

using OIIO::ROI;

namespace {

double max_radius(OIIO::ImageBuf& dst, const FloatPixels& pixels,
                  const FloatPixels& radii, int nthreads)
{
    const ROI& roi = radii.roi();
    std::vector<double> row_max(roi.height(), 0.0);
    OIIO::parallel_for(roi.ybegin, roi.yend, [&](int y) {
        double m = 0.0;
        for (int x = roi.xbegin; x < roi.xend; ++x)
            if (!is_zero(pixels(x, y), pixels.nchannels()))
                m = std::max(m, double(*radii(x, y)));
        row_max[y - roi.ybegin] = m;
    }, OIIO::paropt(nthreads));
    const double m = row_max.empty() ? 0.0 : *std::max_element(row_max.begin(), row_max.end());
    // Beyond this a footprint would not fit in memory: a clamped CoC never
    // comes near it.
    const double limit = 1 << 20;
    if (!(m <= limit)) {
        dst.errorfmt("spread: CoC radius {} is out of range (limit {})", m, limit);
        return -1.0;
    }
    return m;
}

}  // namespace

SpreadInputs prepare_spread(OIIO::ImageBuf& dst, const OIIO::ImageBuf& src,
                            const OIIO::ImageBuf& radius, ROI roi, int nthreads)
{
    SpreadInputs in;
    if (!src.initialized() || !radius.initialized()) {
        dst.errorfmt("spread: uninitialized input");
        return in;
    }
    if (radius.nchannels() != 1) {
        dst.errorfmt("spread: the radius image must have one channel, not {}",
                     radius.nchannels());
        return in;
    }
    if (!roi.defined())
        roi = src.roi();
    roi.chbegin = 0;
    roi.chend   = src.nchannels();
    roi.zbegin = 0;
    roi.zend   = 1;
    if (!src.roi().contains(roi) || !radius.roi().contains(roi.xbegin, roi.ybegin)
        || !radius.roi().contains(roi.xend - 1, roi.yend - 1)) {
        dst.errorfmt("spread: the region {} is not inside both the image {} and the radius {}",
                     roi, src.roi(), radius.roi());
        return in;
    }
    in.roi = roi;
    in.nchannels = src.nchannels();
    in.pixels = FloatPixels(src, roi);
    in.radii = FloatPixels(radius, ROI(roi.xbegin, roi.xend, roi.ybegin,
                                       roi.yend, 0, 1, 0, 1));
    in.max_radius = max_radius(dst, in.pixels, in.radii, nthreads);
    in.valid = in.max_radius >= 0.0;
    return in;
}

ImageSpec output_spec(const OIIO::ImageBuf& src, const ROI& window)
{
    ImageSpec spec(window, OIIO::TypeFloat);
    spec.nchannels = src.nchannels();
    spec.channelnames = src.spec().channelnames;
    spec.alpha_channel = src.spec().alpha_channel;
    spec.full_x = src.spec().full_x;
    spec.full_y = src.spec().full_y;
    spec.full_width = src.spec().full_width;
    spec.full_height = src.spec().full_height;
    return spec;
}

}  // namespace defocus
