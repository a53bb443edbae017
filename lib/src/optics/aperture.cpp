#include <defocus/optics/aperture.h>

#include "util/parse_name.h"

namespace defocus {

bool parse_aperture_shape(const std::string& name, ApertureShape& shape)
{
    return parse_name(name,
                      { ApertureShape::Box, ApertureShape::Disc, ApertureShape::Polygon,
                        ApertureShape::Tent, ApertureShape::Smooth, ApertureShape::Mask },
                      aperture_shape_name, shape);
}

Aperture effective_aperture(const Aperture& aperture, double pixel_aspect)
{
    Aperture squeezed = aperture;
    squeezed.aspect /= pixel_aspect;
    return squeezed;
}

const char* aperture_shape_name(ApertureShape shape)
{
    switch (shape) {
    case ApertureShape::Box: return "box";
    case ApertureShape::Disc: return "disc";
    case ApertureShape::Polygon: return "polygon";
    case ApertureShape::Tent: return "tent";
    case ApertureShape::Smooth: return "smooth";
    case ApertureShape::Mask: return "mask";
    }
    return "?";
}

}  // namespace defocus
