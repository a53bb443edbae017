// An aperture shape as rows of intervals: what scanline spreading writes.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Imath/ImathVec.h>
#include <OpenImageIO/imagebuf.h>

#include <defocus/optics/aperture.h>
#include <defocus/spread/footprint.h>

namespace defocus {

/// One row of a footprint: offset `row` from the anchor pixel, covering
/// [left, right] (pixel units, relative to the shape's centre) with
/// intensity `weight`. Its length times its weight is its share of the
/// shape's area.
struct RowSpan {
    int row;
    double left, right;
    double weight = 1.0;
};

/// A constant-intensity aperture shape, scaled to each pixel's CoC radius.
class RowProfile {
public:
    virtual ~RowProfile() = default;

    /// The exact spans of the shape at CoC radius r (at least half a pixel,
    /// so that an in-focus pixel stays within itself), centred on the
    /// anchor pixel's centre, and their total weighted length: the area.
    virtual double rows(double r, std::vector<RowSpan>& spans) const = 0;

    /// How far the shape reaches from its centre per unit of radius.
    virtual double extent() const = 0;
};

/// A convex aperture outline scaled to each pixel's CoC radius r: a disc
/// of radius r, or a polygon (rounded, rotated) inscribed in it, as render
/// cameras draw their blades; either squeezed keeping its area. Each row [j - 1/2, j + 1/2] is one
/// interval with the shape's exact area in that row, centred on the area's
/// centre.
class ApertureProfile final : public RowProfile {
public:
    explicit ApertureProfile(const Aperture& aperture);

    double rows(double r, std::vector<RowSpan>& spans) const override;
    double extent() const override { return m_extent; }

private:
    /// Area and first moment in x of the unit shape below height y.
    void integrals(double y, double& area, double& moment) const;
    double segment_area(int i, double f) const;  ///< of sample segment i, up to fraction f
    double segment_moment(int i, double f) const;

    std::vector<double> m_left, m_right;   ///< unit chord at m_ymin + i * m_ystep
    std::vector<double> m_area, m_moment;  ///< integrated up to sample i
    double m_ymin = 0, m_ymax = 0, m_ystep = 1;
    double m_extent = 1;
};

/// The box aperture as rows: the square of the CoC disc's area
/// (box_footprint), or the rectangle `aspect` times as wide as tall of that
/// area, for filters that cut shapes row by row.
class BoxProfile final : public RowProfile {
public:
    explicit BoxProfile(double aspect = 1.0)
        : m_aspect(aspect)
    {
    }

    double rows(double r, std::vector<RowSpan>& spans) const override;
    double extent() const override;

private:
    double m_aspect;
};

/// An aperture shape taken from an image (`--aperture mask:FILE`): its
/// luminance thresholded at half its maximum, centred on its centroid,
/// scaled to the area of the CoC disc and squeezed by `aspect`. Any shape,
/// holes and all: each footprint row is the mask's runs at eight sub-rows,
/// each an eighth of the row.
class MaskProfile final : public RowProfile {
public:
    /// The shape drawn in `mask` (its luminance, R, G and B weighted by
    /// `luma`, thresholded at half its peak), squeezed horizontally by
    /// `aspect`. False with `error` saying why (read the file with
    /// read_aperture_mask).
    bool set_shape(const OIIO::ImageBuf& mask, double aspect, const Imath::V3d& luma,
                   std::string& error);

    /// The same shape squeezed horizontally by a further `factor`, keeping
    /// its area.
    std::shared_ptr<const MaskProfile> squeezed(double factor) const;

    double rows(double r, std::vector<RowSpan>& spans) const override;
    double extent() const override { return m_extent; }

private:
    /// m_extent from the runs and the scales.
    void measure_extent();

    struct Run {
        int begin, end;  ///< mask columns [begin, end)
    };
    std::vector<std::vector<Run>> m_runs;  ///< per mask row
    double m_cx = 0, m_cy = 0;             ///< centroid, mask pixels
    double m_sx = 1, m_sy = 1;             ///< unit-shape units per mask pixel
    double m_extent = 1;
};

/// The footprint of exact scanline spreading (spread_scanline) with
/// `profile`: at CoC radius r, the shapes of the two nearest radii on a
/// grid of a quarter pixel, blended linearly, so that it grows
/// continuously.
/// The direct reference for spread_scanline.
Psf aperture_psf(std::shared_ptr<const RowProfile> profile);

}  // namespace defocus
