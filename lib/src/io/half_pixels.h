// Internal: float pixels converted to half for writing, in parallel.
#pragma once

#include <OpenImageIO/imagebuf.h>

namespace defocus {

/// `src` (float, local pixels) as half in `dst`, when the processor
/// converts in hardware (F16C: the same rounding to nearest even as
/// Imath's half); false, leaving `dst` alone, otherwise. OpenImageIO
/// converts on one thread as it writes: 0.1 s of a 4K frame's write.
bool convert_to_half(const OIIO::ImageBuf& src, OIIO::ImageBuf& dst, int nthreads = 0);

}  // namespace defocus
