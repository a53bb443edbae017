// Reading layered scenes from files.
#pragma once

#include <string>

#include <defocus/scene.h>

namespace defocus {

/// Reads a layered scene:
///  - a multi-part EXR (or any multi-subimage file) whose parts are layers,
///    each with R,G,B,A (premultiplied) and Z, each with its own data window;
///  - a single image with R,G,B,A and Z, taken as a one-layer scene.
/// On failure returns false and sets `error` to a one-line message that
/// names the file and the problem.
bool read_scene(const std::string& filename, Scene& scene, std::string& error);

}  // namespace defocus
