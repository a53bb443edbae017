// A layered scene: what every input format is decoded into.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

namespace defocus {

/// One layer: premultiplied colour and its planar camera-space depth over
/// the same data window. A layer need not be planar.
struct Layer {
    std::string name;
    OIIO::ImageBuf color;  ///< float R,G,B,A, alpha_channel = 3
    OIIO::ImageBuf depth;  ///< float Z
};

struct Scene {
    std::string source;   ///< the file it came from, for messages
    /// Display window, pixel type and metadata of the input, kept for the
    /// output. Its data window is the union of the layers'.
    OIIO::ImageSpec spec;
    std::vector<Layer> layers;
};

/// What sanitize() changed, so that -v can say it.
struct PixelCounts {
    int64_t nonfinite_color = 0;  ///< NaN or inf in R,G,B or A: dropped
    int64_t bad_depth       = 0;  ///< Z NaN, zero or negative: moved to infinity
    int64_t transparent_light = 0;  ///< alpha <= 0 with colour: dropped
};

/// Makes every layer safe to spread, and counts what it changed:
///  - a pixel with NaN or inf colour or alpha is dropped (made transparent);
///  - a pixel with alpha <= 0 carries no light: it is cleared whatever its
///    colour and depth (renders write Z = 0 or 1e10 there);
///  - a covered pixel with depth NaN, -inf, zero or negative is taken as
///    infinitely far (+inf is a valid depth: the sky).
PixelCounts sanitize(Scene& scene, int nthreads = 0);

}  // namespace defocus
