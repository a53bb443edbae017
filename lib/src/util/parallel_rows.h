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

}  // namespace defocus
