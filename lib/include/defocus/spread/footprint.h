// Point spread functions as explicit weight tables, for the direct
// reference filters. The fast filters never build these.
#pragma once

#include <functional>
#include <vector>

namespace defocus {

/// The weights one pixel spreads onto its neighbours. Entry (i, j) is the
/// weight at offset (x0 + i, y0 + j) from the pixel; the weights sum to 1.
struct Footprint {
    int x0 = 0, y0 = 0;
    int width = 0, height = 0;
    std::vector<double> weights;  ///< row-major, width * height

    double at(int i, int j) const { return weights[size_t(j) * width + i]; }
};

/// A PSF family: the footprint of a pixel whose CoC radius is `radius`.
using Psf = std::function<Footprint(double radius)>;

/// Half the side of the square with the area of a CoC disc of radius r
/// (r·√π/2), never less than half a pixel so that an in-focus pixel covers
/// exactly itself.
double box_half_width(double coc_radius);

/// The half-widths across and down of the rectangle `aspect` times as wide
/// as tall with the area of a CoC disc of radius r (the box squeezed as
/// --aspect squeezes the other apertures), each at least half a pixel.
struct BoxHalfWidths {
    double x, y;
};
BoxHalfWidths box_half_widths(double coc_radius, double aspect);

/// The box PSF: a square of half-width box_half_width(r) centred on the
/// pixel centre, each pixel weighted by the area of it the square covers.
Footprint box_footprint(double coc_radius);

/// The squeezed box's PSF: the rectangle of box_half_widths(r, aspect),
/// weighted so.
Footprint rectangle_footprint(double coc_radius, double aspect);

/// The pixel columns that a 1-D box [centre - h, centre + h] touches, for a
/// pixel centre at index 0 + 0.5, with the covered length of each.
struct BoxEdges {
    int first;      ///< offset of the first touched pixel
    double first_cover;  ///< covered length of the first pixel in [0,1]
    int last;       ///< offset of the pixel holding the right edge
    double last_cover;   ///< covered length of that pixel, in [0,1)
};
BoxEdges box_edges(double half_width);

}  // namespace defocus
