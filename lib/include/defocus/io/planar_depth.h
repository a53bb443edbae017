// A read scene's depths made planar (see optics/depth_kind.h).
#pragma once

#include <string>

#include <defocus/optics/depth_kind.h>
#include <defocus/scene.h>
#include <defocus/shot/shot.h>

namespace defocus {

/// Converts the depth of every layer and flat render pixel and of every
/// deep sample (front and back) of `scene` with `planar`, before the scene
/// is sanitized. False with `error` saying how many pixels or samples that
/// carry light hold a value that means nothing as the kind (NaN; a negative
/// inverse depth), and where the first is (display-window pixels).
bool to_planar_depth(Scene& scene, const PlanarDepth& planar, std::string& error,
                     int nthreads = 0);

/// The kind of a frame's depth, and where that was said: the setting's
/// label, "file: defocus:depthKind", or "default".
struct DepthChoice {
    DepthKind kind = DepthKind::Z;
    std::string origin = "default";
};

/// What the depth of a shot's inputs holds, whose (first) header is
/// `header`: the shot's setting when given, else what the header declares,
/// else a CoC map when the depth is the channel the coc AOV writes.
DepthChoice frame_depth_kind(const Shot& shot, const OIIO::ImageSpec& header);

/// to_planar_depth() of a read scene of `shot` at `frame`, as `depth`
/// says, the rays those of the shot's lens (lens_camera).
bool planar_scene_depth(const Shot& shot, int frame, const DepthChoice& depth, Scene& scene,
                        std::string& error, int nthreads = 0);

}  // namespace defocus
