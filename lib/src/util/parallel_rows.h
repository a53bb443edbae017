// Internal: how the library's loops over rows are cut into tasks.
#pragma once

#include <OpenImageIO/parallel.h>

namespace defocus {

/// Options for OIIO's parallel_for over rows (or bands, block rows,
/// columns: items of much work each). OIIO's default suits loops over
/// pixels: it runs a range of fewer than 1024 items on the calling thread
/// and cuts a larger one into tasks of at least 1024, so a picture of fewer
/// rows would be made by one thread and a 4K frame by at most two.
inline OIIO::paropt by_rows(int nthreads)
{
    return OIIO::paropt(nthreads).minitems(1);
}

/// Runs task(i) for every i in [begin, end), each item a task of its own,
/// taken by whichever thread is free: for loops over a few dozen items of
/// uneven work (bands of a layer that is blurred more at the bottom).
/// OIIO's parallel_for hands out runs of neighbouring items, so one thread
/// can be left with a costly run while the others wait.
template<typename Task>
void parallel_for_each_item(int64_t begin, int64_t end, Task&& task, int nthreads)
{
    OIIO::parallel_for_chunked(begin, end, 1, [&](int64_t first, int64_t last) {
        for (int64_t i = first; i < last; ++i)
            task(i);
    }, by_rows(nthreads));
}

}  // namespace defocus
