// Internal: fresh memory made ready before it is written.
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <cstdint>

#include <OpenImageIO/parallel.h>

#include "util/parallel_rows.h"

namespace defocus {

/// Maps the pages of a freshly allocated buffer before it is written, in
/// one call per thread: a large image's first writes would otherwise take
/// one page fault per 4 KB (a 4K frame's layers and buffers take 280,000,
/// a seventh of its time), each costing more than the kernel's own batch.
/// Contents are unchanged; without MADV_POPULATE_WRITE (Linux < 5.14)
/// nothing is done.
inline void prefault(void* buffer, size_t bytes, int nthreads)
{
#ifdef MADV_POPULATE_WRITE
    constexpr size_t page = 4096, piece = size_t(16) << 20;
    if (bytes < piece)
        return;
    const uintptr_t begin = (reinterpret_cast<uintptr_t>(buffer) + page - 1) & ~(page - 1);
    const uintptr_t end = (reinterpret_cast<uintptr_t>(buffer) + bytes) & ~(page - 1);
    const int64_t pieces = int64_t((end - begin + piece - 1) / piece);
    OIIO::parallel_for(int64_t(0), pieces, [&](int64_t i) {
        const uintptr_t a = begin + size_t(i) * piece;
        const uintptr_t b = a + piece < end ? a + piece : end;
        madvise(reinterpret_cast<void*>(a), b - a, MADV_POPULATE_WRITE);
    }, by_rows(nthreads));
#else
    (void)buffer;
    (void)bytes;
    (void)nthreads;
#endif
}

}  // namespace defocus
