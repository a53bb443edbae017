// Optical vignetting, the "cat's eye" bokeh: towards the frame's edges the
// lens barrel clips the aperture, so a pixel's bokeh becomes the aperture's
// shape intersected with a second disc of the CoC's radius, offset from
// the pixel towards the optical centre.
#pragma once

#include <Imath/ImathVec.h>
#include <OpenImageIO/imagebuf.h>

#include <defocus/spread/aperture_profile.h>
#include <defocus/spread/footprint.h>

namespace defocus {

/// The barrel's clip over a frame. Positions are in pixel coordinates, the
/// centre of pixel (i, j) at (i + 1/2, j + 1/2).
struct CatEye {
    /// 0: no clip; 1: at the display window's farthest corner the clip
    /// disc's edge reaches the aperture's centre.
    double amount = 0.0;
    Imath::V2d centre { 0.0, 0.0 };  ///< the optical centre
    double corner_distance = 1.0;    ///< from the centre to the farthest display corner

    /// The clip disc's centre relative to the footprint's centre, for a
    /// pixel centred at `at` with CoC radius r: towards the optical centre,
    /// amount · r · (distance from the centre / corner_distance) away.
    Imath::V2d offset(const Imath::V2d& at, double r) const
    {
        return (centre - at) * (amount * r / corner_distance);
    }
};

/// The CoC radius below which nothing is clipped: an in-focus pixel stays
/// itself.
constexpr double cateye_min_radius = 1.0;

/// Scanline spreading (spread_scanline) of a constant-intensity shape
/// clipped by `cateye`: each footprint row is cut into 3 sub-rows, each an
/// interval of the shape (area-exact, from profile.rows()) intersected with
/// the clip disc's chord at its middle, written as edge deltas; one prefix
/// sum along x integrates them. Convex shapes give one interval per
/// sub-row, masks their runs. The cost per pixel grows with its radius
/// (3 sub-rows per row); each pixel's footprint is normalised, so the sum
/// of dst equals the sum of src. dst covers every pixel they reach.
bool spread_cateye(OIIO::ImageBuf& dst, const OIIO::ImageBuf& src, const OIIO::ImageBuf& radius,
                   const RowProfile& profile, const CatEye& cateye, OIIO::ROI roi = {},
                   int nthreads = 0);

/// The same clip for a PSF given as weight tables (the tent and smooth
/// apertures, a PSF image): each footprint pixel whose centre lies outside
/// the clip disc is dropped and the rest renormalised. O(r²) per pixel.
bool spread_cateye(OIIO::ImageBuf& dst, const OIIO::ImageBuf& src, const OIIO::ImageBuf& radius,
                   const Psf& psf, const CatEye& cateye, OIIO::ROI roi = {}, int nthreads = 0);

/// The footprint that spread_cateye(profile) gives a pixel centred at `at`
/// with CoC radius r, as a weight table: the direct reference.
Footprint cateye_footprint(const RowProfile& profile, const CatEye& cateye, const Imath::V2d& at,
                           double r);

}  // namespace defocus
