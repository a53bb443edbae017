#include <defocus/composite/confidence.h>

#include <algorithm>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/parallel.h>

#include <defocus/shot/options.h>

#include "util/float_pixels.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// `scene`'s layers with each pixel's colour made by `pick(rgb, by, out)`
/// from its colour and how it was rebuilt (RebuiltBy::Seen where it was
/// seen), its alpha and depth as they are; false when nothing was rebuilt.
template<typename Pick>
bool part_of(const LayeredScene& scene, LayeredScene& part, Pick pick, int nthreads)
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
                const RebuiltBy by
                    = marked.contains(x, y)
                          ? RebuiltBy(*static_cast<const uint8_t*>(layer.rebuilt.pixeladdr(x, y)))
                          : RebuiltBy::Seen;
                pick(in, by, out);
                out[3] = in[3];
            }
        }, by_rows(nthreads));
        any |= marked.npixels() > 0;
        part.layers.push_back(std::move(rebuilt));
    }
    return any;
}

/// The share of `light` that `share` is, within [0, 1]. The spread's
/// running sums leave a residue of about a millionth where rebuilt light
/// passed by: none.
float share_of(double share, double light)
{
    const double fraction = light > 0.0 ? share / light : 0.0;
    return fraction > 1e-6 ? float(std::min(fraction, 1.0)) : 0.0f;
}

}  // namespace

bool rebuilt_part(const LayeredScene& scene, LayeredScene& part, int nthreads)
{
    return part_of(scene, part, [](const float* rgb, RebuiltBy by, float* out) {
        for (int i = 0; i < 3; ++i)
            out[i] = by != RebuiltBy::Seen ? rgb[i] : 0.0f;
    }, nthreads);
}

bool rebuilt_by_method(const LayeredScene& scene, LayeredScene& part, int nthreads)
{
    const Imath::V3d luma = scene.luma;
    return part_of(scene, part, [luma](const float* rgb, RebuiltBy by, float* out) {
        const float light = float(luma.x * rgb[0] + luma.y * rgb[1] + luma.z * rgb[2]);
        out[0] = by == RebuiltBy::Patterns ? light : 0.0f;
        out[1] = by == RebuiltBy::Lines ? light : 0.0f;
        out[2] = by == RebuiltBy::Smooth ? light : 0.0f;
    }, nthreads);
}

bool light_fraction(ImageBuf& dst, const ImageBuf& all, const ImageBuf& part,
                    const ImageBuf& by_method, const Imath::V3d& luma, int nthreads)
{
    const ROI roi = all.roi();
    if (part.roi() != roi || by_method.roi() != roi || all.nchannels() < 3
        || part.nchannels() < 3 || by_method.nchannels() < 3) {
        dst.errorfmt("light_fraction: the images differ in window or have no colour");
        return false;
    }
    ImageSpec spec(roi, TypeFloat);
    spec.channelnames = aov_channel_names(Aov::Confidence);
    spec.nchannels = int(spec.channelnames.size());
    spec.full_x = all.spec().full_x;
    spec.full_y = all.spec().full_y;
    spec.full_width = all.spec().full_width;
    spec.full_height = all.spec().full_height;
    dst.reset(spec, InitializePixels::No);
    const FloatPixels whole(all, roi), rebuilt(part, roi), methods(by_method, roi);
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        float* out = static_cast<float*>(dst.pixeladdr(roi.xbegin, y));
        for (int x = roi.xbegin; x < roi.xend; ++x, out += 5) {
            const float *a = whole(x, y), *p = rebuilt(x, y), *m = methods(x, y);
            const double light = luma.x * a[0] + luma.y * a[1] + luma.z * a[2];
            const float all = share_of(luma.x * p[0] + luma.y * p[1] + luma.z * p[2], light);
            const float patterns = std::min(share_of(m[0], light), all);
            const float lines = std::min(share_of(m[1], light), all - patterns);
            const float smooth = std::min(share_of(m[2], light), all - patterns - lines);
            // What the three do not hold was continued behind edges.
            const float continued = std::max(all - patterns - lines - smooth, 0.0f);
            // aov_channel_names' order.
            const float shares[5] = { all, continued, lines, patterns, smooth };
            std::copy(shares, shares + 5, out);
        }
    }, by_rows(nthreads));
    return true;
}

}  // namespace defocus
