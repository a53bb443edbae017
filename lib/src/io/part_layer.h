// Internal: one part of a scene file, and how it is read as a layer.
#pragma once

#include <string>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>

#include <defocus/scene.h>

#include "io/exr_input.h"
#include "io/part_channels.h"

namespace defocus {

/// A part of a file that the scene reads: its index, its header, a label
/// for messages, and where its colour and depth are.
struct Part {
    int subimage;
    OIIO::ImageSpec spec;
    std::string label;
    Channels channels;
};

/// Reads every channel of a flat part as float.
bool read_pixels(OIIO::ImageInput& in, const Part& part, OIIO::ImageBuf& pixels,
                 const std::string& filename, std::string& error);

/// Sets a layer's depth from channel `channel` of `depth`, an image over
/// another window. Depth it does not cover is 0, which sanitize() treats
/// as missing.
void lay_depth(Layer& layer, const OIIO::ImageBuf& depth, int channel);

/// A one-channel float image over `window` of a part whose header is
/// `from` (display window), its pixels not yet set.
OIIO::ImageBuf depth_image(const OIIO::ROI& window, const OIIO::ImageSpec& from);

/// A flat layer: colour from `color_part` (opaque without alpha) and, unless
/// `depth_part` is null, depth from the same part or another one.
bool read_layer(const ExrInput& exr, OIIO::ImageInput& in, const std::string& filename,
                const std::string& name, const Part& color_part, const Part* depth_part,
                Layer& layer, std::string& error);

/// Sets a layer's `data` to those of the channels `names` that `part` has,
/// as float over the part's data window; leaves it null when it has none.
bool read_data_channels(const ExrInput& exr, OIIO::ImageInput& in, const std::string& filename,
                        const Part& part, const std::vector<std::string>& names, Layer& layer,
                        std::string& error);

}  // namespace defocus
