// Internal: where in an image something is.
#pragma once

#include <algorithm>
#include <utility>
#include <vector>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/parallel.h>

#include "util/parallel_rows.h"

namespace defocus {

/// The bounding box of the pixels (x, y) of `roi` where marked(x, y) is
/// true, with 4 channels; empty (width 0) when there are none. Rows are
/// scanned in parallel, each from both ends, so that a large marked area
/// costs little more than its outline.
template<typename Marked>
OIIO::ROI bounding_box(const OIIO::ROI& roi, Marked&& marked, int nthreads)
{
    // Per row, the first and last marked column (first > last: none).
    std::vector<std::pair<int, int>> rows(roi.height(), { roi.xend, roi.xbegin - 1 });
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

}  // namespace defocus
