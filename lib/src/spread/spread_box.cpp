// Constant-time rectangle spreading: Kosloff, Tao & Barsky, "Depth of
// Field Postprocessing for Layered Scenes Using Constant-Time Rectangle
// Spreading", GI 2009, section 3, with fractional edge coverage.
#include <defocus/spread/spread.h>

#include "spread/spread_common.h"

namespace defocus {

bool spread_box(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius, ROI roi,
                int nthreads)
{
    return spread_box(dst, src, radius, 1.0, roi, nthreads);
}

bool spread_box(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius, double aspect,
                ROI roi, int nthreads)
{
    return spread_image(dst, src, radius, roi, nthreads, SpreadMethod::Box, nullptr, {}, {},
                        aspect);
}

}  // namespace defocus
