#include <defocus/color/bloom.h>

#include <algorithm>
#include <atomic>

#include <OpenImageIO/parallel.h>

#include "util/parallel_rows.h"

namespace defocus {

namespace {

/// Where the ramp up to the full gain starts, as a share of the threshold.
constexpr double ramp_start = 0.9;

/// Lifts premultiplied (r, g, b) of alpha `a`; true when it did.
bool lift(const Bloom& bloom, float& r, float& g, float& b, float a)
{
    if (!(a > 0.0f))
        return false;
    const double factor = bloom.factor(r / a, g / a, b / a);
    if (factor == 1.0)
        return false;
    r = float(r * factor);
    g = float(g * factor);
    b = float(b * factor);
    return true;
}

}  // namespace

double Bloom::factor(double r, double g, double b) const
{
    const double brightest = std::max({ r, g, b });
    const double t = std::clamp((brightest - ramp_start * threshold)
                                    / ((1.0 - ramp_start) * threshold),
                                0.0, 1.0);
    return 1.0 + (gain - 1.0) * t * t * (3.0 - 2.0 * t);
}

int64_t apply_bloom(Scene& scene, const Bloom& bloom, int nthreads)
{
    std::atomic<int64_t> lifted { 0 };
    for_each_content(scene,
        [&](Layer& layer) {
            const OIIO::ROI roi = layer.color.roi();
            OIIO::parallel_for(roi.ybegin, roi.yend, [&](int y) {
                float* c = static_cast<float*>(layer.color.pixeladdr(roi.xbegin, y));
                int64_t row = 0;
                for (int x = 0; x < roi.width(); ++x, c += 4)
                    row += lift(bloom, c[0], c[1], c[2], c[3]);
                lifted += row;
            }, by_rows(nthreads));
            return true;
        },
        [&](DeepImage& image) {
            OIIO::parallel_for_chunked(int64_t(0), int64_t(image.samples.size()), 0,
                                       [&](int64_t begin, int64_t end) {
                int64_t chunk = 0;
                for (int64_t i = begin; i < end; ++i) {
                    DeepSample& s = image.samples[size_t(i)];
                    chunk += lift(bloom, s.r, s.g, s.b, s.a);
                }
                lifted += chunk;
            }, OIIO::paropt(nthreads));
            return true;
        });
    return lifted;
}

}  // namespace defocus
