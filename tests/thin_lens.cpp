#include "thin_lens.h"

#include <algorithm>
#include <cmath>

namespace defocus_test {

using OIIO::ImageBuf;
using OIIO::ROI;

namespace {

/// A layer's lit pixels: where each is, its radius and its light.
struct LitPixel {
    int x, y;
    float radius;
    float rgba[4];
};

std::vector<LitPixel> lit_pixels(const LensLayer& layer)
{
    std::vector<LitPixel> lit;
    const ROI roi = layer.color.roi();
    for (int y = roi.ybegin; y < roi.yend; ++y)
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            LitPixel p { x, y, 0.0f, {} };
            layer.color.getpixel(x, y, p.rgba);
            if (p.rgba[0] == 0.0f && p.rgba[1] == 0.0f && p.rgba[2] == 0.0f && p.rgba[3] == 0.0f)
                continue;
            layer.radius.getpixel(x, y, &p.radius);
            lit.push_back(p);
        }
    return lit;
}

/// A layer seen through aperture point (ux, uy): each pixel's light moved
/// by its radius times u, split bilinearly; RGBA over `window`.
void shifted(const std::vector<LitPixel>& layer, double ux, double uy, const ROI& window,
             std::vector<double>& out)
{
    std::fill(out.begin(), out.end(), 0.0);
    for (const LitPixel& p : layer) {
        // The pixel's corner lands here; the four it overlaps share it.
        const double tx = p.x + p.radius * ux, ty = p.y + p.radius * uy;
        const int ix = int(std::floor(tx)), iy = int(std::floor(ty));
        const double fx = tx - ix, fy = ty - iy;
        const double w[4] = { (1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy };
        for (int k = 0; k < 4; ++k) {
            const int px = ix + (k & 1), py = iy + (k >> 1);
            if (!window.contains(px, py))
                continue;
            double* o
                = &out[(size_t(py - window.ybegin) * window.width() + (px - window.xbegin)) * 4];
            for (int c = 0; c < 4; ++c)
                o[c] += w[k] * p.rgba[c];
        }
    }
}

}  // namespace

ImageBuf thin_lens(const std::vector<LensLayer>& back_to_front, const ROI& window, int samples,
                   const LensClip& clip)
{
    const size_t n = size_t(window.npixels()) * 4;
    std::vector<std::vector<LitPixel>> layers;
    for (const LensLayer& l : back_to_front)
        layers.push_back(lit_pixels(l));
    std::vector<double> sum(n, 0.0), composite(n), layer(n);
    std::vector<int> count(n / 4, 0);
    for (int j = 0; j < samples; ++j)
        for (int i = 0; i < samples; ++i) {
            const double ux = -1.0 + (i + 0.5) * 2.0 / samples,
                         uy = -1.0 + (j + 0.5) * 2.0 / samples;
            if (ux * ux + uy * uy > 1.0)
                continue;
            std::fill(composite.begin(), composite.end(), 0.0);
            for (const std::vector<LitPixel>& l : layers) {
                shifted(l, ux, uy, window, layer);
                for (size_t p = 0; p < n; p += 4) {
                    const double a = layer[p + 3];
                    const double scale = a > 1.0 ? 1.0 / a : 1.0;
                    const double alpha = std::clamp(a, 0.0, 1.0);
                    for (int c = 0; c < 3; ++c)
                        composite[p + c] = layer[p + c] * scale + (1.0 - alpha) * composite[p + c];
                    composite[p + 3] = alpha + (1.0 - alpha) * composite[p + 3];
                }
            }
            for (size_t p = 0; p < n / 4; ++p) {
                if (clip
                    && !clip(ux, uy, window.xbegin + int(p % window.width()),
                             window.ybegin + int(p / window.width())))
                    continue;
                ++count[p];
                for (int c = 0; c < 4; ++c)
                    sum[p * 4 + c] += composite[p * 4 + c];
            }
        }
    OIIO::ImageSpec spec(window.width(), window.height(), 4, OIIO::TypeFloat);
    spec.x = window.xbegin;
    spec.y = window.ybegin;
    ImageBuf out(spec);
    for (int y = window.ybegin; y < window.yend; ++y)
        for (int x = window.xbegin; x < window.xend; ++x) {
            const size_t at = size_t(y - window.ybegin) * window.width() + (x - window.xbegin);
            const double* s = &sum[at * 4];
            const double k = std::max(count[at], 1);
            const float p[4] = { float(s[0] / k), float(s[1] / k), float(s[2] / k),
                                 float(s[3] / k) };
            out.setpixel(x, y, p);
        }
    return out;
}

double psnr_over(const ImageBuf& image, const ImageBuf& reference, const ROI& roi)
{
    double peak = 0.0, squared = 0.0;
    for (int y = roi.ybegin; y < roi.yend; ++y)
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            float a[4], b[4];
            image.getpixel(x, y, a);
            reference.getpixel(x, y, b);
            for (int c = 0; c < 3; ++c) {
                peak = std::max(peak, double(b[c]));
                squared += (double(a[c]) - b[c]) * (double(a[c]) - b[c]);
            }
        }
    const double mse = squared / (3.0 * double(roi.npixels()));
    return 10.0 * std::log10(peak * peak / std::max(mse, 1e-30));
}

}  // namespace defocus_test
