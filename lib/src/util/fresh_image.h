// Internal: fresh images, made fast.
#pragma once

#include <cstring>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/parallel.h>

#include "util/parallel_rows.h"
#include "util/prefault.h"

namespace defocus {

/// Resets `image` to `spec` (local pixels) with its pixels unset, for a
/// caller that writes every one of them; its pages are mapped already.
inline void reset_for_overwrite(OIIO::ImageBuf& image, const OIIO::ImageSpec& spec, int nthreads)
{
    image.reset(spec, OIIO::InitializePixels::No);
    prefault(image.localpixels(), spec.image_bytes(), nthreads);
}

/// Resets `image` to `spec` (local pixels) with every pixel zero. OIIO's
/// own zero-initialisation goes through its pixel iterator, which costs
/// a 4K frame more than spreading a sparse layer into it.
inline void reset_zeroed(OIIO::ImageBuf& image, const OIIO::ImageSpec& spec, int nthreads)
{
    reset_for_overwrite(image, spec, nthreads);
    char* pixels = static_cast<char*>(image.localpixels());
    const size_t row_bytes = spec.scanline_bytes();
    OIIO::parallel_for(int64_t(0), int64_t(spec.height) * spec.depth, [&](int64_t row) {
        std::memset(pixels + size_t(row) * row_bytes, 0, row_bytes);
    }, by_rows(nthreads));
}

}  // namespace defocus
