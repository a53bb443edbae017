// The shape of the lens opening, which is the shape of the bokeh.
#pragma once

#include <string>

namespace defocus {

enum class ApertureShape {
    Box,      ///< a square of the CoC disc's area: constant-time rectangle spreading
    Disc,     ///< the CoC disc, spread scanline by scanline
    Polygon,  ///< an iris of `blades` straight (or rounded) blades, inscribed in the CoC disc
    Tent,     ///< a smooth second-order PSF (two boxes convolved), constant time
    Smooth,   ///< a third-order B-spline PSF, close to a Gaussian, constant time
    Mask,     ///< a shape taken from an image, spread scanline by scanline
};

struct Aperture {
    ApertureShape shape = ApertureShape::Disc;
    int blades = 6;             ///< polygon: 3..16
    /// polygon: clockwise in the image, as renderers turn blades; 0 = a
    /// vertex pointing right
    double rotation_deg = 0.0;
    double roundness = 0.0;     ///< polygon: 0 = straight edges, 1 = a disc
    /// Anamorphic squeeze: < 1 narrows the bokeh horizontally (disc,
    /// polygon, mask and box; tent and smooth stay round)
    double aspect = 1.0;
    std::string mask_file;      ///< mask: the image of the shape
};

/// The aperture as a plate's pixels draw it: squeezed by a further
/// 1 / `pixel_aspect` (keeping its area), so that the desqueezed image
/// shows its own shape. Tent and smooth take no squeeze.
Aperture effective_aperture(const Aperture& aperture, double pixel_aspect);

/// "box", "disc", "polygon", "tent", "smooth" or "mask"; false for any
/// other name.
bool parse_aperture_shape(const std::string& name, ApertureShape& shape);
const char* aperture_shape_name(ApertureShape shape);

}  // namespace defocus
