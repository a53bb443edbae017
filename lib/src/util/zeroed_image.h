// Internal: a fresh float image with every pixel zero, made fast.
#pragma once

#include <cstring>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/parallel.h>

#include "util/parallel_rows.h"
#include "util/prefault.h"

namespace defocus {

/// Resets `image` to `spec` (local pixels) with every pixel zero. OIIO's
/// own zero-initialisation goes through its pixel iterator, which costs
/// a 4K frame more than spreading a sparse layer into it; rows cleared in
/// parallel also spread the first-touch page faults over the threads.
inline void reset_zeroed(OIIO::ImageBuf& image, const OIIO::ImageSpec& spec, int nthreads)
{
    image.reset(spec, OIIO::InitializePixels::No);
    char* pixels = static_cast<char*>(image.localpixels());
    prefault(pixels, spec.image_bytes(), nthreads);
    const size_t row_bytes = spec.scanline_bytes();
    OIIO::parallel_for(int64_t(0), int64_t(spec.height) * spec.depth, [&](int64_t row) {
        std::memset(pixels + size_t(row) * row_bytes, 0, row_bytes);
    }, by_rows(nthreads));
}

}  // namespace defocus
