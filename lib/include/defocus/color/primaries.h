// How a colour space is named in an image file: OpenEXR's chromaticities
// and the Color Interop Forum's colorInteropID, so that a result reads
// back in the space it was written in, and an input says which it is in.
#pragma once

#include <array>
#include <string>

#include <OpenImageIO/imageio.h>

#include <defocus/color/color.h>

namespace defocus {

/// A colour space that files can name: by its CIE xy chromaticities (red,
/// green and blue primaries, then the white point: OpenEXR's and OIIO's
/// "chromaticities", float[8]) and by its colorInteropID.
struct KnownSpace {
    const char* description;  ///< "ACES AP1", "Rec.709"...
    const char* interop_id;   ///< "lin_ap1_scene"...
    const char* names[3];     ///< the names a config may give it, canonical or alias
    std::array<float, 8> chromaticities;
    bool linear;
};

/// The known space that is `space` (a space of `config`), or null.
const KnownSpace* known_space(const ColorManagement& config, const std::string& space);

/// The linear known space whose chromaticities match `xy` (within 0.001),
/// or null.
const KnownSpace* linear_space_with_chromaticities(const float xy[8]);

/// The known space of a colorInteropID, or null.
const KnownSpace* space_with_interop_id(const std::string& id);

/// The space of `config` that is `known`, or "" when the config has none.
std::string config_space(const ColorManagement& config, const KnownSpace& known);

/// Records in `spec` which space its pixels are in: the chromaticities and
/// colorInteropID of a known space; a space files cannot name has neither,
/// so none is carried over from an input in another space.
void record_color_space(OIIO::ImageSpec& spec, const ColorManagement& config,
                        const std::string& space);

}  // namespace defocus
