// Spreading aperture shapes (discs, polygons, masks): exactly, scanline by
// scanline (Kosloff, Tao & Barsky 2009, section 4.1), or in bounded time
// per pixel, merging the pixels of large footprints into blocks; clipped
// by a cat's eye too.
#include <defocus/spread/cateye.h>
#include <defocus/spread/spread.h>

#include "spread/spread_common.h"

namespace defocus {

bool spread_scanline(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius,
                     const RowProfile& profile, ROI roi, int nthreads)
{
    return spread_image(dst, src, radius, roi, nthreads, SpreadMethod::Exact, &profile);
}

bool spread_aperture(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius,
                     const RowProfile& profile, const HighlightTest& highlights, ROI roi,
                     int nthreads)
{
    return spread_image(dst, src, radius, roi, nthreads, SpreadMethod::Bounded, &profile,
                        highlights);
}

bool spread_cateye_bounded(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius,
                           const RowProfile& profile, const CatEye& cateye,
                           const HighlightTest& highlights, ROI roi, int nthreads)
{
    return spread_image(dst, src, radius, roi, nthreads, SpreadMethod::Bounded, &profile,
                        highlights, cateye);
}

}  // namespace defocus
