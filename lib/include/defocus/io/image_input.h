// Reading a whole image file, as float, the way it is on disk now.
#pragma once

#include <string>

#include <OpenImageIO/imagebuf.h>

namespace defocus {

/// Why `filename` cannot be opened as an image file ("no such file", "is a
/// directory, not an image", "not a regular file": a device or a pipe
/// would keep a format probe reading forever), or null when it can.
const char* not_a_file(const std::string& filename);

/// Reads the first subimage of `filename`, every channel, as float, into
/// `dst`. Goes around OpenImageIO's shared ImageCache: it keeps a file's
/// size from the first time it was opened, and OpenImageIO 2.4 writes a
/// file rewritten larger under the same name past the buffer sized from
/// it. On failure `error` reads "FILE: cannot read WHAT: why", `what`
/// saying what the file was for (e.g. "the aperture mask").
bool read_image_file(const std::string& filename, const std::string& what, OIIO::ImageBuf& dst,
                     std::string& error);

}  // namespace defocus
