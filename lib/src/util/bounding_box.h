// Internal: where in an image something is.
#pragma once

#include <algorithm>
#include <utility>
#include <vector>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/parallel.h>

#include "util/parallel_rows.h"

namespace defocus {

/// Per row of an ROI, the first and last column of something (first >
/// last: none in that row).
using RowRanges = std::vector<std::pair<int, int>>;

/// The ranges of no column in any of `roi`'s rows.
inline RowRanges empty_rows(const OIIO::ROI& roi)
{
    return RowRanges(roi.height(), { roi.xend, roi.xbegin - 1 });
}

/// The bounding box of `rows` over `roi`, with 4 channels; empty (width 0)
/// when no row has any column.
inline OIIO::ROI box_of_rows(const OIIO::ROI& roi, const RowRanges& rows)
{
    OIIO::ROI box(roi.xend, roi.xbegin, roi.yend, roi.ybegin, 0, 1, 0, 4);
    for (int y = roi.ybegin; y < roi.yend; ++y)
        if (const auto& [first, last] = rows[y - roi.ybegin]; first <= last) {
            box.xbegin = std::min(box.xbegin, first);
            box.xend = std::max(box.xend, last + 1);
            box.ybegin = std::min(box.ybegin, y);
            box.yend = y + 1;
        }
    return box.xend > box.xbegin ? box : OIIO::ROI(0, 0, 0, 0, 0, 1, 0, 4);
}

/// The bounding box of the pixels (x, y) of `roi` where marked(x, y) is
/// true, with 4 channels; empty (width 0) when there are none. Rows are
/// scanned in parallel, each from both ends, so that a large marked area
/// costs little more than its outline.
template<typename Marked>
OIIO::ROI bounding_box(const OIIO::ROI& roi, Marked&& marked, int nthreads)
{
    RowRanges rows = empty_rows(roi);  // the marked columns
    OIIO::parallel_for(roi.ybegin, roi.yend, [&](int y) {
        int first = roi.xbegin;
        while (first < roi.xend && !marked(first, y))
            ++first;
        if (first == roi.xend)
            return;
        int last = roi.xend - 1;
        while (!marked(last, y))
            --last;
        rows[y - roi.ybegin] = { first, last };
    }, by_rows(nthreads));
    return box_of_rows(roi, rows);
}

}  // namespace defocus
