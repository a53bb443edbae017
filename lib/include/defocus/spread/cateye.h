// Optical vignetting, the "cat's eye" bokeh: towards the frame's edges the
// lens barrel clips the aperture, so a pixel's bokeh becomes the aperture's
// shape intersected with a second disc of the CoC's radius, offset from
// the pixel towards the optical centre; in front of the focus, away from
// it (the bokeh is the lens seen mirrored there, and so is its clip).
#pragma once

#include <cmath>
#include <memory>
#include <vector>

#include <Imath/ImathVec.h>
#include <OpenImageIO/imagebuf.h>

#include <defocus/spread/aperture_profile.h>
#include <defocus/spread/footprint.h>
#include <defocus/spread/hybrid.h>

namespace defocus {

/// The barrel's clip over a frame. Positions are in pixel coordinates, the
/// centre of pixel (i, j) at (i + 1/2, j + 1/2).
struct CatEye {
    /// 0: no clip; 1: at the display window's farthest corner the clip
    /// disc's edge reaches the aperture's centre.
    double amount = 0.0;
    Imath::V2d centre { 0.0, 0.0 };  ///< the optical centre
    /// From the centre to the farthest display corner; on a plate of
    /// pixel aspect a, measured on the desqueezed image and divided by
    /// sqrt(a), so that offset() is that of the desqueezed image.
    double corner_distance = 1.0;
    /// The clip's width over its height in pixels: 1 / the pixel aspect,
    /// as the aperture is squeezed (effective_aperture). The clip has the
    /// area of the CoC disc.
    double clip_aspect = 1.0;
    /// 1 for what lies behind the focus, -1 in front of it: a near point's
    /// light lands at p + rho u from lens point u with rho < 0, so its
    /// footprint is the clipped lens turned half a turn.
    double side = 1.0;

    /// The clip disc's centre relative to the footprint's centre, for a
    /// pixel centred at `at` with CoC radius r: towards the optical centre
    /// (away from it on the near side), amount · r · (distance from the
    /// centre / corner_distance) away.
    Imath::V2d offset(const Imath::V2d& at, double r) const
    {
        return (centre - at) * (side * amount * r / corner_distance);
    }

    /// The clip of a layer whose CoC reaches from coc_min to coc_max (signed,
    /// negative in front of the focus): the side of its largest blur.
    CatEye of_layer(double coc_min, double coc_max) const
    {
        CatEye layer = *this;
        const double widest = std::abs(coc_min) > std::abs(coc_max) ? coc_min : coc_max;
        layer.side = widest < 0.0 ? -1.0 : 1.0;
        return layer;
    }
};

/// The CoC radius below which nothing is clipped: an in-focus pixel stays
/// itself.
constexpr double cateye_min_radius = 1.0;

/// A cell of a grid on which the bounded-time cat's eye
/// (spread_cateye_bounded) takes the clip's offset per unit of radius:
/// a grid of step cateye_cell_size / 2^fineness, cell (x, y) centred on
/// (x, y) steps.
struct CatEyeCell {
    int x, y, fineness;
    bool operator==(const CatEyeCell& o) const
    {
        return x == o.x && y == o.y && fineness == o.fineness;
    }
    bool operator!=(const CatEyeCell& o) const { return !(*this == o); }
};

/// The step of the grid of fineness 0: a footprint of radius r clipped at
/// its cell's centre has the clip's edge within r / 64 of where its own
/// offset puts it.
constexpr double cateye_cell_size = 1.0 / 32.0;

/// The grid that a pixel (block 1) of CoC radius r takes, or a merged
/// block of `block` pixels: fine enough that the clip's edge lies within
/// r / 64 but at most half a pixel of the pixel's own (a highlight's bokeh
/// shows its outline); blocks take the coarsest, r / 64 being at most a
/// quarter of a block at the radii it is merged at.
int cateye_fineness(int block, double r);

/// The cell of the offset per unit of radius, cateye.offset(at, 1), on the
/// grid of `fineness`.
CatEyeCell cateye_cell(const CatEye& cateye, const Imath::V2d& at, int fineness = 0);

/// The offset per unit of radius at the centre of `cell`.
Imath::V2d cateye_cell_offset(const CatEyeCell& cell);

/// An aperture shape clipped by the barrel with a fixed offset per unit of
/// radius: at CoC radius r (from cateye_min_radius), the shape cut by the
/// disc of radius r centred r times `offset_per_radius` away. Each row is
/// cut into 3 sub-rows, each an interval of the shape (area-exact, from
/// aperture.rows()) intersected with the clip disc's chord at its middle.
/// Where the clip leaves nothing, and with `clip` false, the sub-rows are
/// uncut: those bound every clipped shape's reach.
class ClippedProfile final : public RowProfile {
public:
    ClippedProfile(std::shared_ptr<const RowProfile> aperture,
                   const Imath::V2d& offset_per_radius, double clip_aspect, bool clip = true);

    double rows(double r, std::vector<RowSpan>& spans) const override;
    double extent() const override { return m_aperture->extent(); }

private:
    std::shared_ptr<const RowProfile> m_aperture;
    Imath::V2d m_offset;
    double m_clip_aspect;
    bool m_clip;
};

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

/// The same clip in bounded time per pixel, as spread_aperture spreads the
/// unclipped shape: pixels of CoC radius below 7.5 and the highlights that
/// pass `highlights` alone, larger footprints merged in blocks. Each pixel
/// or block takes the clipped shape (ClippedProfile) of the cell
/// (cateye_cell, on the grid of cateye_fineness) of its centre; below
/// radius 7.5 a pixel's footprint is aperture_psf of that shape. The sum of dst equals the sum of src.
bool spread_cateye_bounded(OIIO::ImageBuf& dst, const OIIO::ImageBuf& src,
                           const OIIO::ImageBuf& radius, const RowProfile& profile,
                           const CatEye& cateye, const HighlightTest& highlights = {},
                           OIIO::ROI roi = {}, int nthreads = 0);

/// The footprint that spread_cateye(profile) gives a pixel centred at `at`
/// with CoC radius r, as a weight table: the direct reference.
Footprint cateye_footprint(const RowProfile& profile, const CatEye& cateye, const Imath::V2d& at,
                           double r);

}  // namespace defocus
