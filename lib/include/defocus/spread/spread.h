// Spreading filters on one layer, in the style of ImageBufAlgo: each takes
// const ImageBuf inputs, an ROI and a thread count, writes `dst`, and
// returns false with dst.geterror() set on failure.
//
// Inputs for all of them:
//   src     premultiplied colour (any number of channels, usually RGBA);
//   radius  one float channel: the CoC radius |c|/2 in pixels of each
//           source pixel, over at least `roi`.
// `roi` is the region of src to spread (default: src's data window).
#pragma once

#include <OpenImageIO/imagebuf.h>

#include <defocus/spread/aperture_profile.h>
#include <defocus/spread/footprint.h>
#include <defocus/spread/hybrid.h>

namespace defocus {

using OIIO::ImageBuf;
using OIIO::ROI;

/// Constant-time rectangle spreading (Kosloff, Tao & Barsky 2009): each
/// pixel spreads over the square with the area of its CoC disc, with
/// fractional edge coverage, through corner deltas and two prefix sums.
/// The square's size is blended between the two nearest sizes on a grid of
/// 1/16 pixel of radius (box_footprint). dst covers every pixel the
/// squares reach, in float; the sum of dst equals the sum of src.
bool spread_box(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius,
                ROI roi = {}, int nthreads = 0);

/// spread_box() with rectangles `aspect` times as wide as tall, of the same
/// area (box_half_widths): the box squeezed as --aspect squeezes the other
/// apertures.
bool spread_box(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius, double aspect,
                ROI roi = {}, int nthreads = 0);

/// Exact scanline spreading of a constant-intensity shape (Kosloff, Tao &
/// Barsky 2009, sec. 4.1): each row of each pixel's footprint is an
/// interval written as edge deltas with fractional coverage, integrated
/// horizontally once. The cost per pixel is the footprint's height. Its
/// footprints are aperture_psf(profile). dst covers every pixel they
/// reach; its sum equals src's.
bool spread_scanline(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius,
                     const RowProfile& profile, ROI roi = {}, int nthreads = 0);

/// Pixels brighter than this many times the mean over their CoC square
/// (see HighlightTest) are spread exactly by spread_aperture, never merged.
/// Lower than the hybrid method's default: merging may move a pixel, and on
/// the garden scene keeping those pixels in place is worth 0.015 dB.
constexpr double exact_highlight_threshold = 2.0;

/// The same shapes in bounded time per pixel, whatever the blur. Pixels of
/// CoC radius below 7.5, and the highlights that pass `highlights` (the
/// frame pipeline's threshold is exact_highlight_threshold), are spread
/// exactly, as spread_scanline does. Larger footprints are
/// merged: the pixels of one size in a block of s x s pixels (s = 2, 4, ...
/// 32, at most r/4) are spread once, blocks of up to 4 with the footprint
/// of a uniform block (each pixel's shape on its own centre, so a uniform
/// area stays exact), larger ones from their centre; the work per pixel
/// is bounded whatever the radius. Radii just below a change of
/// block size are spread both ways, blended, so footprints change
/// continuously. Energy is conserved exactly; dst covers every pixel the
/// footprints reach.
bool spread_aperture(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius,
                     const RowProfile& profile, const HighlightTest& highlights = {},
                     ROI roi = {}, int nthreads = 0);

/// Smooth PSFs in constant time by repeated integration: order 2 is the
/// tent (two boxes convolved), order 3 a quadratic B-spline (three boxes),
/// close to a Gaussian. The box width matches the CoC disc's variance,
/// blended between two integer widths so that the PSF grows continuously.
/// The integration down the columns is exact (64-bit fixed point, and
/// 128-bit for pixels in short runs), whatever the radius: rows filtered
/// as runs are within about 2^-31 of the layer's largest value at radius
/// 200. At most 8 channels.
bool spread_smooth(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius, int order,
                   ROI roi = {}, int nthreads = 0);

/// The same PSF as spread_smooth's, as a table, for the direct reference.
Footprint smooth_footprint(int order, double coc_radius);

/// Direct spreading: every pixel adds psf(radius) times its value to its
/// neighbours. O(r²) per pixel; the reference the fast filters must equal.
/// dst covers `roi` grown by the largest footprint.
bool spread_direct(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius,
                   const Psf& psf, ROI roi = {}, int nthreads = 0);

/// Gathering, the baseline the tests show failing: each output pixel is the
/// psf-weighted average of its neighbours at its *own* radius. dst covers
/// `roi`.
bool gather(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius,
            const Psf& psf, ROI roi = {}, int nthreads = 0);

}  // namespace defocus
