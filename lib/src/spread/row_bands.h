// Internal: parallel scheduling for filters that scatter.
#pragma once

#include <algorithm>

#include <OpenImageIO/parallel.h>

#include "util/parallel_rows.h"

namespace defocus {

/// Run fn(band_begin, band_end) over [begin, end) split into one band of
/// destination rows per thread. A scattering filter writes rows anywhere
/// within its reach of the source row, so each band is owned by exactly
/// one thread, which scans every source row that can reach it: there are
/// no write races and no per-thread copies of the output.
template<typename Fn>
void for_each_row_band(int begin, int end, int nthreads, Fn&& fn)
{
    OIIO::paropt opt = by_rows(nthreads);
    opt.resolve();
    const int bands = std::max(1, std::min(opt.maxthreads(), end - begin));
    const int64_t band_rows = (int64_t(end - begin) + bands - 1) / bands;
    OIIO::parallel_for_chunked(
        begin, end, band_rows,
        [&](int64_t b, int64_t e) { fn(int(b), int(e)); }, opt);
}

}  // namespace defocus
