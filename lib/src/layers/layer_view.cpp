#include <defocus/layers/layer_view.h>

#include <cmath>

#include <OpenImageIO/parallel.h>

#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

Imath::V3f layer_colour(int index)
{
    // HSV with saturation 0.8 and value 0.95, the hue turned by the golden
    // angle per layer.
    const double hue = std::fmod(0.08 + index * 0.381966011250105, 1.0) * 6.0;
    const int sector = int(hue);
    const float f = float(hue - sector), v = 0.95f, p = v * 0.2f;
    const float q = v * (1.0f - 0.8f * f), t = v * (1.0f - 0.8f * (1.0f - f));
    switch (sector) {
    case 0: return { v, t, p };
    case 1: return { q, v, p };
    case 2: return { p, v, t };
    case 3: return { p, q, v };
    case 4: return { t, p, v };
    default: return { v, p, q };
    }
}

bool layer_view(ImageBuf& dst, const LayeredScene& scene, int nthreads)
{
    const ImageSpec spec = display_picture_spec(scene);
    const ROI display = spec.roi();
    dst.reset(spec);  // transparent where no layer covers
    parallel_for(display.ybegin, display.yend, [&](int y) {
        for (int x = display.xbegin; x < display.xend; ++x) {
            float* p = static_cast<float*>(dst.pixeladdr(x, y));
            for (size_t l = 0; l < scene.layers.size(); ++l) {
                const Layer& layer = scene.layers[l];
                if (!layer.color.roi().contains(x, y))
                    continue;
                const float a = static_cast<const float*>(layer.color.pixeladdr(x, y))[3];
                if (!(a > 0.0f))
                    continue;
                const Imath::V3f c = layer_colour(int(l));
                for (int i = 0; i < 3; ++i)
                    p[i] = c[i] * a + p[i] * (1.0f - a);
                p[3] = a + p[3] * (1.0f - a);
            }
        }
    }, by_rows(nthreads));
    return true;
}

}  // namespace defocus
