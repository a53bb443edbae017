#include <defocus/spread/footprint.h>

#include <algorithm>
#include <cmath>

namespace defocus {

double box_half_width(double coc_radius)
{
    const double sqrt_pi_over_2 = 0.88622692545275801365;
    return std::max(0.5, coc_radius * sqrt_pi_over_2);
}

BoxHalfWidths box_half_widths(double coc_radius, double aspect)
{
    const double squeeze = std::sqrt(aspect);
    return { box_half_width(coc_radius * squeeze), box_half_width(coc_radius / squeeze) };
}

BoxEdges box_edges(double h)
{
    // The box spans [0.5 - h, 0.5 + h] around the pixel [0, 1).
    const double a = 0.5 - h, b = 0.5 + h;
    const double fa = std::floor(a), fb = std::floor(b);
    return { int(fa), 1.0 - (a - fa), int(fb), b - fb };
}

namespace {

/// The coverage of each pixel a 1-D box of half-width h touches,
/// normalised by 2h, from the first touched pixel's offset.
std::vector<double> box_weights(double h, int& first)
{
    const BoxEdges e = box_edges(h);
    first = e.first;
    // h >= 0.5 puts the edges in different pixels, so there are 2 or more.
    std::vector<double> w(size_t(e.last - e.first + 1), 1.0);
    w.front() = e.first_cover;
    w.back()  = e.last_cover;
    for (double& v : w)
        v /= 2.0 * h;
    return w;
}

}  // namespace

Footprint box_footprint(double coc_radius)
{
    return rectangle_footprint(coc_radius, 1.0);
}

Footprint rectangle_footprint(double coc_radius, double aspect)
{
    const BoxHalfWidths h = box_half_widths(coc_radius, aspect);
    Footprint fp;
    const std::vector<double> wx = box_weights(h.x, fp.x0), wy = box_weights(h.y, fp.y0);
    fp.width = int(wx.size());
    fp.height = int(wy.size());
    fp.weights.resize(wx.size() * wy.size());
    for (int j = 0; j < fp.height; ++j)
        for (int i = 0; i < fp.width; ++i)
            fp.weights[size_t(j) * fp.width + i] = wx[i] * wy[j];
    return fp;
}

}  // namespace defocus
