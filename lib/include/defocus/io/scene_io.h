// Reading layered scenes from files.
#pragma once

#include <string>

#include <OpenImageIO/imageio.h>
#include <vector>

#include <defocus/scene.h>
#include <defocus/shot/options.h>

namespace defocus {

/// Reads a scene from one or several files.
///
/// One file may be:
///  - a multi-part EXR whose parts each hold R,G,B,A (premultiplied) and Z:
///    the parts are the layers;
///  - a flat render: one part with R,G,B,A and Z, or an RGBA part and a
///    part holding the depth (Z or depth.Z) of the same view, joined;
///  - a deep image (deepscanline or deeptile), one or more parts.
/// Colour without alpha (R,G,B only) is taken as opaque.
/// In a multi-view file only the parts of the chosen view (and parts with
/// no view) are read. Several files are layers of one scene: a flat file
/// among them is one layer, and all deep images are merged into one (each
/// pixel keeps the samples of all), so that they interleave by depth. The
/// first file gives the display window and metadata; the others must share
/// its display window.
///
/// Every EXR's headers are checked by OpenEXR's core library before
/// OpenImageIO opens it, so corrupt files end in an error rather than a
/// crash, and a chunk larger than the memory limit is refused before
/// OpenEXR allocates it. On failure returns
/// false and sets `error` to a one-line message naming the file and the
/// problem.
bool read_scene(const std::vector<std::string>& filenames,
                const ReadOptions& options, Scene& scene, std::string& error);

/// What the files' headers declare, as float: every part's pixels times
/// its channels (a deep part's samples are not in its header: one a pixel).
/// A measure of how much reading them takes, before they are read; a file
/// that cannot be opened, or whose one chunk `limit` cannot decode, counts
/// nothing (reading it says why).
double declared_bytes(const std::vector<std::string>& filenames, const MemoryLimit& limit);

/// The spec read_scene() would give the scene (display window, metadata,
/// the union of the data windows read), from the files' headers alone,
/// without reading or vetting pixels.
bool read_scene_spec(const std::vector<std::string>& filenames, const ReadOptions& options,
                     OIIO::ImageSpec& spec, std::string& error);

}  // namespace defocus
