// Internal: which channels of an image part hold a layer's colour,
// alpha and depth.
#pragma once

#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

namespace defocus {

std::string channel_name(const std::string& prefix, const std::string& channel);

/// Where one part keeps a layer's colour and depth; -1 where it has none.
struct Channels {
    std::string prefix;                 ///< of the colour channels
    int color[4] = { -1, -1, -1, -1 };  ///< R,G,B,A; A is -1 in colour without alpha
    int depth    = -1;

    bool has_color() const { return color[0] >= 0; }
    bool has_alpha() const { return color[3] >= 0; }
    bool has_depth() const { return depth >= 0; }
};

/// The first channel of `names` the part has, or -1.
int first_channel(const OIIO::ImageSpec& spec, const std::vector<std::string>& names);

/// Resolves the colour and depth channels of one part. Colour is R,G,B,A
/// (or, when no set has A, R,G,B) under the chosen prefix (--layer, also
/// with Blender's ".Combined"), or plain, or the part's only prefixed set.
/// Sets without A are passed over when one has it: they are a render's
/// colour passes (diffuse, albedo), not its beauty. Depth is Z next to the colour,
/// Blender's <viewlayer>.Depth.Z, or a depth pass named Z or depth.Z.
/// `error` is set when the choice is ambiguous.
Channels find_channels(const OIIO::ImageSpec& spec, const std::string& layer,
                       std::string& error);

/// The first of R,G,B,Z a part lacks, for messages.
std::string missing_channel(const OIIO::ImageSpec& spec, const std::string& layer);

}  // namespace defocus
