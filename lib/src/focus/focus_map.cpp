#include <defocus/focus/focus_map.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/parallel.h>

#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

bool focus_map(ImageBuf& dst, const LayeredScene& scene, const Camera& camera,
               double in_focus_px, int nthreads)
{
    const ImageSpec spec = display_picture_spec(scene);
    const ROI display = spec.roi();
    dst.reset(spec, InitializePixels::No);  // every pixel is written below
    const CircleOfConfusion coc(camera, scene.spec.roi_full());
    const double max_blur = std::max(camera.max_blur_px, 1e-6);
    parallel_for(display.ybegin, display.yend, [&](int y) {
        for (int x = display.xbegin; x < display.xend; ++x) {
            // The front-most surface that covers the pixel.
            double z = std::numeric_limits<double>::infinity();
            bool covered = false;
            for (const Layer& layer : scene.layers) {
                if (!layer.color.roi().contains(x, y))
                    continue;
                const float a = static_cast<const float*>(layer.color.pixeladdr(x, y))[3];
                const float d = *static_cast<const float*>(layer.depth.pixeladdr(x, y));
                if (a > 0.5f && (!covered || d < z)) {
                    z = d;
                    covered = true;
                }
            }
            float* p = static_cast<float*>(dst.pixeladdr(x, y));
            if (!covered) {
                p[0] = p[1] = p[2] = p[3] = 0.0f;
                continue;
            }
            const double c = coc.diameter(z, x, y);
            const double t = std::min(1.0, std::abs(c) / in_focus_px);
            // Brightness grows with the blur, on a log scale up to max blur.
            const double size = std::log2(1.0 + std::abs(c)) / std::log2(1.0 + max_blur);
            const double shade = t * (0.4 + 0.6 * std::min(1.0, size));
            p[0] = float(c < 0.0 ? shade : 0.0);
            p[1] = float(1.0 - t);
            p[2] = float(c > 0.0 ? shade : 0.0);
            p[3] = 1.0f;
            if (std::abs(c) >= max_blur)  // clamped: half way to white
                for (int i = 0; i < 3; ++i)
                    p[i] = 0.5f * (p[i] + 1.0f);
        }
    }, by_rows(nthreads));
    return true;
}

}  // namespace defocus
