// The memory-bandwidth floor of spreading: what any spreading of a layer
// must at least move through memory.
#pragma once

#include <vector>

namespace bench {

/// One float RGBA layer (premultiplied, alpha 0 where it is empty) and a
/// signed CoC diameter in pixels per pixel.
struct FloorLayer {
    int width = 0, height = 0;
    std::vector<float> color, coc;
};

/// Four 4096x2160 layers, blur up to 100 px: a far field (CoC 60 px), hills
/// over the lower half (10 to 40 px), an in-focus post over a tenth of the
/// width, and near leaves over a quarter of the frame (-100 px).
std::vector<FloorLayer> make_floor_layers();

/// Seconds to read every layer's RGBA and depth once, and to read and
/// write a float RGBA accumulator of its size once per axis (the two
/// prefix sums), on every core.
double memory_floor(const std::vector<FloorLayer>& layers);

}  // namespace bench
