#include <defocus/spread/footprint.h>

#include <algorithm>
#include <cmath>

namespace defocus {

double box_half_width(double coc_radius)
{
    const double sqrt_pi_over_2 = 0.88622692545275801365;
    return std::max(0.5, coc_radius * sqrt_pi_over_2);
}

BoxEdges box_edges(double h)
{
    // The box spans [0.5 - h, 0.5 + h] around the pixel [0, 1).
    const double a = 0.5 - h, b = 0.5 + h;
    const double fa = std::floor(a), fb = std::floor(b);
    return { int(fa), 1.0 - (a - fa), int(fb), b - fb };
}

Footprint box_footprint(double coc_radius)
{
    const double h = box_half_width(coc_radius);
    const BoxEdges e = box_edges(h);
    const int n = e.last - e.first + 1;
    // Coverage of each touched pixel along one axis, normalised by 2h.
    std::vector<double> w(n, 1.0);
    // h >= 0.5 puts the edges in different pixels, so n >= 2.
    w.front() = e.first_cover;
    w.back()  = e.last_cover;
    for (double& v : w)
        v /= 2.0 * h;

    Footprint fp;
    fp.x0 = fp.y0 = e.first;
    fp.width = fp.height = n;
    fp.weights.resize(size_t(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            fp.weights[size_t(j) * n + i] = w[i] * w[j];
    return fp;
}

}  // namespace defocus
