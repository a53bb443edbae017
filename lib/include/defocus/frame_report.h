// What a rendered frame did, as text for people: the camera and where its
// values came from, colour, layers, pixel fixes and per-stage timings (the
// defocus command's -v), and its display-referred preview.
#pragma once

#include <string>

#include <OpenImageIO/imagebuf.h>

#include <defocus/render_frame.h>
#include <defocus/shot/shot.h>

namespace defocus {

/// The report of `frame` of `shot`, written to `output`: indented lines,
/// each ending in a newline.
std::string frame_report(const FrameResult& frame, const Shot& shot, const std::string& output);

/// The display window of `frame` through an OpenColorIO display and view
/// ("" for the config's defaults), as 8-bit display-referred pixels to look
/// at; over black unless `keep_alpha`. False with `error` when the frame
/// has no config or the display or view is unknown.
bool preview_image(const FrameResult& frame, const std::string& display, const std::string& view,
                   bool keep_alpha, OIIO::ImageBuf& preview, std::string& error);

}  // namespace defocus
