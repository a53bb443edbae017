// Internal: where a scene's flat and deep content is cut into layers.
#pragma once

#include <vector>

#include <defocus/layers/layering.h>
#include <defocus/optics/camera.h>
#include <defocus/scene.h>

#include "layers/blur_field.h"

namespace defocus {

/// choose_layer_bounds (layering.h) over the blur fields of the scene's
/// flat renders, already made.
LayerBounds layer_bounds(const Scene& scene, const std::vector<BlurField>& flats,
                         const CircleOfConfusion& coc, const LayeringOptions& options,
                         int nthreads);

}  // namespace defocus
