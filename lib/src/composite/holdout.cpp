#include <defocus/composite/holdout.h>

#include <algorithm>
#include <cmath>

#include <OpenImageIO/parallel.h>

#include "util/float_pixels.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// Calls on_sample(x, y, sample) for every sample of `scene`: deep samples
/// as they are, covered pixels of layers and flat renders as one each.
template<typename OnSample>
void for_each_sample(const Scene& scene, OnSample&& on_sample)
{
    for_each_content(
        scene,
        [&](const Layer& layer) {
            const ROI own = layer.color.roi();
            const FloatPixels color(layer.color, own);
            const FloatPixels depth(layer.depth, ROI(own.xbegin, own.xend, own.ybegin, own.yend,
                                                     0, 1, 0, 1));
            for (int y = own.ybegin; y < own.yend; ++y)
                for (int x = own.xbegin; x < own.xend; ++x) {
                    const float* c = color(x, y);
                    const float z = *depth(x, y);
                    if (c[3] > 0.0f)
                        on_sample(x, y, DeepSample { c[0], c[1], c[2], c[3], z, z });
                }
            return true;
        },
        [&](const DeepImage& deep) {
            for (int y = deep.roi.ybegin; y < deep.roi.yend; ++y)
                for (int x = deep.roi.xbegin; x < deep.roi.xend; ++x) {
                    const int64_t i = deep.pixel_index(x, y);
                    for (uint64_t s = deep.offsets[i]; s < deep.offsets[i + 1]; ++s)
                        on_sample(x, y, deep.samples[s]);
                }
            return true;
        });
}

}  // namespace

DeepImage holdout_image(const Scene& scene)
{
    DeepImage holdout;
    holdout.name = scene.source;
    ROI roi;
    for_each_content(
        scene, [&](const Layer& layer) { roi = roi_union(roi, layer.color.roi()); return true; },
        [&](const DeepImage& deep) { roi = roi_union(roi, deep.roi); return true; });
    if (!roi.defined() || roi.npixels() == 0)
        return holdout;
    holdout.roi = ROI(roi.xbegin, roi.xend, roi.ybegin, roi.yend);
    // Counted, then placed: one array of samples, not a vector a pixel.
    std::vector<uint64_t>& offsets = holdout.offsets;
    offsets.assign(size_t(holdout.roi.npixels()) + 1, 0);
    for_each_sample(scene, [&](int x, int y, const DeepSample&) {
        ++offsets[holdout.pixel_index(x, y) + 1];
    });
    for (size_t i = 1; i < offsets.size(); ++i)
        offsets[i] += offsets[i - 1];
    holdout.samples.resize(offsets.back());
    std::vector<uint64_t> next(offsets.begin(), offsets.end() - 1);
    for_each_sample(scene, [&](int x, int y, const DeepSample& sample) {
        holdout.samples[next[holdout.pixel_index(x, y)]++] = sample;
    });
    parallel_for(int64_t(0), int64_t(offsets.size() - 1), [&](int64_t i) {
        std::stable_sort(holdout.samples.begin() + offsets[i],
                         holdout.samples.begin() + offsets[i + 1],
                         [](const DeepSample& a, const DeepSample& b) { return a.z < b.z; });
    });
    return holdout;
}

double holdout_transmittance(const DeepImage& holdout, int x, int y, double near, double far)
{
    if (!holdout.roi.contains(x, y))
        return 1.0;
    const int64_t i = holdout.pixel_index(x, y);
    double passed = 1.0;
    for (uint64_t s = holdout.offsets[i]; s < holdout.offsets[i + 1]; ++s) {
        const DeepSample& h = holdout.samples[s];
        if (h.z >= far)
            break;  // sorted front to back
        const double alpha = std::clamp(double(h.a), 0.0, 1.0);
        if (h.zback <= h.z) {
            if (h.z >= near)
                passed *= 1.0 - alpha;
            continue;
        }
        const double inside = std::min<double>(h.zback, far) - std::max<double>(h.z, near);
        if (inside > 0.0)
            passed *= std::pow(1.0 - alpha, inside / (double(h.zback) - h.z));
    }
    return passed;
}

void hold_out(ImageBuf& frame, const DeepImage& holdout, double near, double far, ROI roi,
              int nthreads)
{
    roi = roi_intersection(roi, holdout.roi);
    if (holdout.samples.empty() || roi.npixels() == 0)
        return;
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        float* out = static_cast<float*>(frame.pixeladdr(roi.xbegin, y));
        for (int x = roi.xbegin; x < roi.xend; ++x, out += 4) {
            const double t = holdout_transmittance(holdout, x, y, near, far);
            if (t != 1.0)
                for (int c = 0; c < 4; ++c)
                    out[c] = float(out[c] * t);
        }
    }, by_rows(nthreads));
}

}  // namespace defocus
