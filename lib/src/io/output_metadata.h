// Internal: the metadata a frame's result carries.
#pragma once

#include <OpenImageIO/imageio.h>

#include <defocus/color/color_plan.h>
#include <defocus/optics/camera.h>
#include <defocus/optics/depth_kind.h>
#include <defocus/shot/shot.h>

namespace defocus {

/// The metadata of a result: the input's (less what describes one part),
/// its colour space, the camera (but that of a CoC map: `depth_kind`), and
/// the settings used, with a line of history saying how it was made.
void describe_output(OIIO::ImageSpec& spec, const OIIO::ImageSpec& input, const Shot& shot,
                     const Camera& camera, DepthKind depth_kind, const ColorPlan& color,
                     int frame);

}  // namespace defocus
