// Writing results without ever leaving a half-written file behind.
#pragma once

#include <string>

#include <OpenImageIO/imagebuf.h>

namespace defocus {

/// Writes `image` to `filename` in the format its extension names, as
/// `type` (TypeUnknown: the image's own pixel type) with `compression`
/// ("" for the format's default). The pixels go to a temporary file beside
/// the target, which is renamed over it only once complete, so readers
/// never see a partial file. On failure returns false, sets `error` to a
/// one-line message naming the file, and removes the temporary.
bool write_image_atomic(const OIIO::ImageBuf& image, const std::string& filename,
                        OIIO::TypeDesc type, const std::string& compression,
                        std::string& error);

}  // namespace defocus
