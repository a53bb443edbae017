// Internal: fresh images, made fast.
#pragma once

#include <cstring>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/parallel.h>

#include "util/parallel_rows.h"
#include "util/prefault.h"

namespace defocus {

/// Whether `image` owns pixels laid out as `spec` says (its window and
/// type), which can be written again.
inline bool holds_pixels_like(const OIIO::ImageBuf& image, const OIIO::ImageSpec& spec)
{
    const OIIO::ImageSpec& had = image.spec();
    return image.storage() == OIIO::ImageBuf::LOCALBUFFER && !had.deep && !spec.deep
           && had.format == spec.format && had.nchannels == spec.nchannels
           && had.x == spec.x && had.y == spec.y && had.z == spec.z && had.width == spec.width
           && had.height == spec.height && had.depth == spec.depth;
}

/// Resets `image` to `spec` (local pixels) with its pixels unset, for a
/// caller that writes every one of them; its pages are mapped already.
/// Pixels `image` holds in that layout are kept and written again, as
/// ImageBufAlgo writes into an initialised destination: a sequence that
/// renders into one image skips the fresh pages of a new one (zeroed by
/// the kernel, a page fault each), which cost a 4K frame about 25 ms.
inline void reset_for_overwrite(OIIO::ImageBuf& image, const OIIO::ImageSpec& spec, int nthreads)
{
    if (holds_pixels_like(image, spec)) {
        image.specmod() = spec;
        return;
    }
    image.reset(spec, OIIO::InitializePixels::No);
    prefault(image.localpixels(), spec.image_bytes(), nthreads);
}

/// Sets every pixel of `image` (local or wrapped pixels) to zero but those
/// of `unset` (if defined), which the caller writes. OIIO's own
/// zero-initialisation goes through its pixel iterator, which costs a 4K
/// frame more than spreading a sparse layer into it.
inline void zero_except(OIIO::ImageBuf& image, const OIIO::ROI& unset, int nthreads)
{
    const OIIO::ImageSpec& spec = image.spec();
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

/// Resets `image` to `spec` (local pixels) with every pixel zero but those
/// of `unset` (if defined), which the caller writes.
inline void reset_zeroed_except(OIIO::ImageBuf& image, const OIIO::ImageSpec& spec,
                                const OIIO::ROI& unset, int nthreads)
{
    reset_for_overwrite(image, spec, nthreads);
    zero_except(image, unset, nthreads);
}

/// Resets `image` to `spec` (local pixels) with every pixel zero.
inline void reset_zeroed(OIIO::ImageBuf& image, const OIIO::ImageSpec& spec, int nthreads)
{
    reset_zeroed_except(image, spec, OIIO::ROI(), nthreads);
}

}  // namespace defocus
