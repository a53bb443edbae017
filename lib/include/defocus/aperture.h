// The shape of the lens opening, which is the shape of the bokeh.
#pragma once

#include <string>

namespace defocus {

enum class Aperture {
    Box,  ///< a square of the CoC disc's area: constant-time rectangle spreading
};

/// "box"; false when the name is not an aperture.
bool parse_aperture(const std::string& name, Aperture& aperture);
const char* aperture_name(Aperture aperture);

}  // namespace defocus
