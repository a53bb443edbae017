#include <defocus/shot/aperture.h>

namespace defocus {

bool parse_aperture_shape(const std::string& name, ApertureShape& shape)
{
    if (name == "box")
        shape = ApertureShape::Box;
    else if (name == "disc")
        shape = ApertureShape::Disc;
    else if (name == "polygon")
        shape = ApertureShape::Polygon;
    else if (name == "tent")
        shape = ApertureShape::Tent;
    else if (name == "smooth")
        shape = ApertureShape::Smooth;
    else if (name == "mask")
        shape = ApertureShape::Mask;
    else
        return false;
    return true;
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
