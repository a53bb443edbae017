// The "focal plane setup" view compositors use to place focus.
#pragma once

#include <OpenImageIO/imagebuf.h>

#include <defocus/layers/layered_scene.h>
#include <defocus/optics/camera.h>

namespace defocus {

/// A false-colour RGBA image of where the focus falls, over the scene's
/// display window: for each pixel the front-most covered surface (alpha
/// over 1/2, the nearest of any layer) is green in focus, red in front
/// of the focus plane and blue behind, shading from green over the first
/// `in_focus_px` pixels of CoC, brighter as the CoC grows, and tinted white
/// where the CoC reaches the camera's max blur. Uncovered pixels are
/// transparent.
bool focus_map(OIIO::ImageBuf& dst, const LayeredScene& scene, const Camera& camera,
               double in_focus_px = 8.0, int nthreads = 0);

}  // namespace defocus
