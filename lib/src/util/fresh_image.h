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

/// Resets `image` to `spec` (local pixels) with every pixel zero but those
/// of `unset` (if defined), which the caller writes. OIIO's own
/// zero-initialisation goes through its pixel iterator, which costs a 4K
/// frame more than spreading a sparse layer into it.
inline void reset_zeroed_except(OIIO::ImageBuf& image, const OIIO::ImageSpec& spec,
                                const OIIO::ROI& unset, int nthreads)
{
    reset_for_overwrite(image, spec, nthreads);
    const OIIO::ROI all = image.roi();
    const OIIO::ROI untouched = unset.defined() && spec.depth == 1
                                    ? OIIO::roi_intersection(unset, all)
                                    : OIIO::ROI(0, 0, 0, 0);
    char* pixels = static_cast<char*>(image.localpixels());
    const size_t row_bytes = spec.scanline_bytes(), pixel_bytes = spec.pixel_bytes();
    OIIO::parallel_for(int64_t(0), int64_t(spec.height) * spec.depth, [&](int64_t row) {
        char* p = pixels + size_t(row) * row_bytes;
        const int y = all.ybegin + int(row);
        if (untouched.width() <= 0 || y < untouched.ybegin || y >= untouched.yend) {
            std::memset(p, 0, row_bytes);
            return;
        }
        std::memset(p, 0, size_t(untouched.xbegin - all.xbegin) * pixel_bytes);
        std::memset(p + size_t(untouched.xend - all.xbegin) * pixel_bytes, 0,
                    size_t(all.xend - untouched.xend) * pixel_bytes);
    }, by_rows(nthreads));
}

/// Resets `image` to `spec` (local pixels) with every pixel zero.
inline void reset_zeroed(OIIO::ImageBuf& image, const OIIO::ImageSpec& spec, int nthreads)
{
    reset_zeroed_except(image, spec, OIIO::ROI(), nthreads);
}

}  // namespace defocus
