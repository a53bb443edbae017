#include <defocus/scene.h>

#include <atomic>
#include <cmath>
#include <limits>

#include <OpenImageIO/parallel.h>

namespace defocus {

PixelCounts sanitize(Scene& scene, int nthreads)
{
    std::atomic<int64_t> nonfinite { 0 }, bad_depth { 0 }, transparent { 0 };
    const float infinity = std::numeric_limits<float>::infinity();
    for (Layer& layer : scene.layers) {
        const OIIO::ROI roi = layer.color.roi();
        OIIO::parallel_for(roi.ybegin, roi.yend, [&](int y) {
            int64_t n_nonfinite = 0, n_depth = 0, n_transparent = 0;
            for (int x = roi.xbegin; x < roi.xend; ++x) {
                float* c = static_cast<float*>(layer.color.pixeladdr(x, y));
                float* z = static_cast<float*>(layer.depth.pixeladdr(x, y));
                const bool finite = std::isfinite(c[0]) && std::isfinite(c[1])
                                    && std::isfinite(c[2]) && std::isfinite(c[3]);
                if (!finite || c[3] <= 0.0f) {
                    if (!finite)
                        ++n_nonfinite;
                    else if (c[0] != 0.0f || c[1] != 0.0f || c[2] != 0.0f)
                        ++n_transparent;
                    c[0] = c[1] = c[2] = c[3] = 0.0f;
                    continue;
                }
                if (!(*z > 0.0f)) {
                    ++n_depth;
                    *z = infinity;
                }
            }
            nonfinite += n_nonfinite;
            bad_depth += n_depth;
            transparent += n_transparent;
        }, OIIO::paropt(nthreads));
    }
    return { nonfinite, bad_depth, transparent };
}

}  // namespace defocus
