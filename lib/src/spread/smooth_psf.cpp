#include "spread/smooth_psf.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <defocus/spread/spread.h>

namespace defocus {

Widths smooth_widths(int order, double r)
{
    const double w = std::sqrt(1.0 + 3.0 * r * r / order);
    const int step = order % 2 ? 2 : 1;
    int w0 = std::max(1, int(std::floor(w)));
    if (step == 2 && w0 % 2 == 0)
        --w0;
    const double t = std::clamp((w - w0) / step, 0.0, 1.0);
    return { { w0, w0 + step }, { 1.0 - t, t } };
}

int binomial(int n, int k)
{
    int c = 1;
    for (int i = 0; i < k; ++i)
        c = c * (n - i) / (i + 1);
    return c;
}

namespace {

/// One axis of the order-n box of width w, normalised: the taps from
/// -half_support to +half_support.
std::vector<double> box_power(int order, int w)
{
    std::vector<double> taps { 1.0 };
    for (int k = 0; k < order; ++k) {
        std::vector<double> next(taps.size() + w - 1, 0.0);
        for (size_t i = 0; i < taps.size(); ++i)
            for (int j = 0; j < w; ++j)
                next[i + j] += taps[i] / w;
        taps = std::move(next);
    }
    return taps;
}

}  // namespace

Footprint smooth_footprint(int order, double coc_radius)
{
    const Widths ws = smooth_widths(order, coc_radius);
    const int reach = half_support(order, ws.w[1]);
    std::vector<double> axis(2 * reach + 1, 0.0);
    for (int b = 0; b < 2; ++b) {
        const std::vector<double> taps = box_power(order, ws.w[b]);
        const int h = half_support(order, ws.w[b]);
        for (int i = -h; i <= h; ++i)
            axis[i + reach] += ws.weight[b] * taps[i + h];
    }
    Footprint fp;
    fp.x0 = fp.y0 = -reach;
    fp.width = fp.height = 2 * reach + 1;
    fp.weights.resize(size_t(fp.width) * fp.height);
    for (int j = 0; j < fp.height; ++j)
        for (int i = 0; i < fp.width; ++i)
            fp.weights[size_t(j) * fp.width + i] = axis[i] * axis[j];
    return fp;
}

}  // namespace defocus
