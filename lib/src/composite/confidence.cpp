#include <defocus/composite/confidence.h>

#include <algorithm>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/parallel.h>

#include "util/float_pixels.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

bool rebuilt_part(const LayeredScene& scene, LayeredScene& part, int nthreads)
{
    part = LayeredScene();
    part.source = scene.source;
    part.spec = scene.spec;
    part.luma = scene.luma;
    part.holdout = scene.holdout;  // the rebuilt light is held out as the image is
    part.reports = scene.reports;
    bool any = false;
    for (const Layer& layer : scene.layers) {
        ImageSpec spec = layer.color.spec();
        spec.set_format(TypeFloat);
        // Every pixel is written below.
        Layer rebuilt { layer.name, ImageBuf(spec, InitializePixels::No), layer.depth, {} };
        const ROI roi = layer.color.roi();
        const ROI marked = layer.rebuilt.initialized() ? roi_intersection(layer.rebuilt.roi(), roi)
                                                       : ROI(0, 0, 0, 0, 0, 1, 0, 1);
        const FloatPixels color(layer.color, roi);
        parallel_for(roi.ybegin, roi.yend, [&](int y) {
            float* out = static_cast<float*>(rebuilt.color.pixeladdr(roi.xbegin, y));
            const float* in = color(roi.xbegin, y);
            for (int x = roi.xbegin; x < roi.xend; ++x, in += 4, out += 4) {
                const bool kept = marked.contains(x, y)
                                  && *static_cast<const uint8_t*>(layer.rebuilt.pixeladdr(x, y));
                for (int i = 0; i < 3; ++i)
                    out[i] = kept ? in[i] : 0.0f;
                out[3] = in[3];
            }
        }, by_rows(nthreads));
        any |= marked.npixels() > 0;
        part.layers.push_back(std::move(rebuilt));
    }
    return any;
}

bool light_fraction(ImageBuf& dst, const ImageBuf& all, const ImageBuf& part,
                    const Imath::V3d& luma, int nthreads)
{
    const ROI roi = all.roi();
    if (part.roi() != roi || all.nchannels() < 3 || part.nchannels() < 3) {
        dst.errorfmt("light_fraction: the images differ in window or have no colour");
        return false;
    }
    ImageSpec spec(roi, TypeFloat);
    spec.nchannels = 1;
    spec.channelnames = { "confidence" };
    spec.full_x = all.spec().full_x;
    spec.full_y = all.spec().full_y;
    spec.full_width = all.spec().full_width;
    spec.full_height = all.spec().full_height;
    dst.reset(spec, InitializePixels::No);
    const FloatPixels whole(all, roi), rebuilt(part, roi);
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        float* out = static_cast<float*>(dst.pixeladdr(roi.xbegin, y));
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const float *a = whole(x, y), *p = rebuilt(x, y);
            const double light = luma.x * a[0] + luma.y * a[1] + luma.z * a[2];
            const double share = luma.x * p[0] + luma.y * p[1] + luma.z * p[2];
            // The spread's running sums leave a residue of about a
            // millionth where the rebuilt light passed by: none.
            const double fraction = light > 0.0 ? share / light : 0.0;
            out[x - roi.xbegin] = fraction > 1e-6 ? float(std::min(fraction, 1.0)) : 0.0f;
        }
    }, by_rows(nthreads));
    return true;
}

}  // namespace defocus
