// The gather baseline: what compositing packages' defocus nodes do, kept
// so the tests can show its artifacts.
#include <defocus/spread/spread.h>

#include <algorithm>
#include <vector>

#include <OpenImageIO/parallel.h>

#include "spread/spread_common.h"
#include "util/float_pixels.h"
#include "util/parallel_rows.h"

namespace defocus {

bool gather(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius,
            const Psf& psf, ROI roi, int nthreads)
{
    const SpreadInputs in = prepare_spread(dst, src, radius, roi, nthreads);
    if (!in.valid)
        return false;
    const int nc = in.nchannels;
    roi = in.roi;
    ROI window = roi;
    window.chend = nc;
    dst.reset(output_spec(src, window), OIIO::InitializePixels::No);  // every pixel is written below
    float* out = static_cast<float*>(dst.localpixels());
    OIIO::parallel_for(roi.ybegin, roi.yend, [&](int y) {
        std::vector<double> sum(nc);
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            // The adjoint of spreading with this pixel's own footprint,
            // renormalised over the part that lies inside the image.
            const Footprint fp = psf(*in.radii(x, y));
            std::fill(sum.begin(), sum.end(), 0.0);
            double wsum = 0.0;
            for (int j = 0; j < fp.height; ++j) {
                const int sy = y - (fp.y0 + j);
                if (sy < roi.ybegin || sy >= roi.yend)
                    continue;
                for (int i = 0; i < fp.width; ++i) {
                    const int sx = x - (fp.x0 + i);
                    if (sx < roi.xbegin || sx >= roi.xend)
                        continue;
                    const double w = fp.at(i, j);
                    const float* v = in.pixels(sx, sy);
                    for (int c = 0; c < nc; ++c)
                        sum[c] += w * v[c];
                    wsum += w;
                }
            }
            float* o = out + (size_t(y - roi.ybegin) * roi.width() + (x - roi.xbegin)) * nc;
            for (int c = 0; c < nc; ++c)
                o[c] = wsum > 0.0 ? float(sum[c] / wsum) : 0.0f;
        }
    }, by_rows(nthreads));
    return true;
}

}  // namespace defocus
