// Focusing on a pixel: the focus distance is the depth of what is seen
// there.
#pragma once

#include <string>

#include <defocus/scene.h>
#include <defocus/optics/camera.h>
#include <defocus/io/camera_metadata.h>
#include <defocus/shot/shot.h>

namespace defocus {

/// The depth of the front-most opaque surface at display-window pixel
/// (x, y) (0,0 = the display window's top left), as the median over the
/// `window` rows around it and as many columns as make a square on the
/// desqueezed image (window / `pixel_aspect`, odd). A pixel's front-most opaque
/// surface is where its layers, flat renders and deep samples, composited
/// front to back, first reach half coverage. Works on a sanitized scene
/// before slicing. False with `error` when (x, y) is outside the display
/// window or nothing there is opaque at a finite depth.
bool focus_distance_at(const Scene& scene, double x, double y, double& distance,
                       std::string& error, int window = 5, double pixel_aspect = 1.0);

/// The camera of a shot at `frame` before its focus is known: camera_at();
/// with camera_from_file, the values `header` records (camera_from_header)
/// in place of those the shot does not give; the header's pixel aspect.
/// True when a focus distance was found (the shot's or the header's).
bool lens_camera(const Shot& shot, const OIIO::ImageSpec& header, int frame, Camera& camera,
                 CameraOrigins& origins);

/// The camera of a shot at `frame` over a read scene whose depth is planar:
/// lens_camera(), with the focus measured by focus_distance_at() when the
/// shot focuses at a pixel; then validated. A CoC map's depth (`depth_kind`
/// Coc) has its own camera (coc_map_camera), and refuses focus settings.
/// `origins` says where each value came from. False with `error` the
/// problem.
bool shot_camera(const Shot& shot, const Scene& scene, int frame, Camera& camera,
                 CameraOrigins& origins, std::string& error,
                 DepthKind depth_kind = DepthKind::Z);

}  // namespace defocus
