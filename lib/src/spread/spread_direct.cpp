// The direct spreading reference: O(r²) per pixel, kept for the tests.
#include <defocus/spread/spread.h>

#include "spread/scatter_pixels.h"

namespace defocus {

bool spread_direct(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius,
                   const Psf& psf, ROI roi, int nthreads)
{
    return scatter_pixels(
        dst, src, radius, roi, nthreads,
        [&](double max_radius) { return footprint_reach(psf, max_radius); }, false,
        [&](int x, int y, const float* v, int nc, double r, auto&& row) {
            add_footprint(psf(r), x, y, v, nc, row);
        });
}

}  // namespace defocus
