// What lies beyond the frame's data window when a blur reaches past it.
#pragma once

#include <string>

#include <defocus/layers/layered_scene.h>
#include <defocus/optics/camera.h>
#include <defocus/shot/options.h>

namespace defocus {

/// Extends the layers beyond the frame's data window (scene.spec's) by
/// repeating their outermost pixels, colour and depth, so that a blurred
/// frame does not lose light at its borders: a uniform field stays uniform
/// to the corners. Only the sides where a layer touches the data window are
/// extended, by the reach of its largest blur. Auto does so only where the
/// render was cut off by the frame: on the sides where the data window
/// reaches the display window but not that far past it (overscan); a data
/// window inside the display window bounds the content, with nothing
/// beyond; and not a layer the extension would make more than four times
/// larger (the blur wide against it: what is repeated would outweigh what
/// is there). The extended layers are described again and the layers
/// reordered. Returns the most pixels added on any side (0: none).
int extend_edges(LayeredScene& scene, const CircleOfConfusion& coc, EdgeMode mode,
                 int nthreads = 0);

}  // namespace defocus
