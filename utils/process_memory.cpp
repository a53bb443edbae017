#include "process_memory.h"

#include <climits>  // and with it <features.h>, which says whether this is glibc
#include <fstream>

#include <unistd.h>

#ifdef __GLIBC__
#include <malloc.h>
#endif

namespace defocus {

// glibc serves every block over 32 MB (each 4K image, layer and buffer)
// with a mapping of its own, unmapped when freed; a thread's arena cannot
// hold such blocks either (its heaps stop at 64 MB). The next image's
// pages are then new, and the kernel zeroes each one: 15% of a 4K
// sequence's CPU time. One arena that never maps blocks of their own nor
// trims its top reuses what the last layer or frame freed: a sequence of
// 4K frames took 0.82x the time, for 5% more peak memory (22% for a deep
// file, whose sample lists fragment the heap; see CHANGELOG.md, speed).
// The smallest blocks, the most frequent, come from each thread's cache
// without taking the arena's lock.
void keep_freed_memory()
{
#ifdef __GLIBC__
    mallopt(M_ARENA_MAX, 1);
    mallopt(M_MMAP_MAX, 0);
    mallopt(M_TRIM_THRESHOLD, INT_MAX);
#endif
}

double resident_bytes()
{
    // Linux: the second field of statm, in pages.
    std::ifstream statm("/proc/self/statm");
    double total = 0.0, resident = 0.0;
    if (!(statm >> total >> resident))
        return 0.0;
    const long page = sysconf(_SC_PAGESIZE);
    return page > 0 ? resident * double(page) : 0.0;
}

}  // namespace defocus
