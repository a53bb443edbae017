// An aperture shape as rows of intervals: what scanline spreading writes.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <defocus/aperture.h>
#include <defocus/footprint.h>

namespace defocus {

/// One row of a footprint: offset `row` from the pixel, covering
/// [left, right] (pixel units, relative to the pixel centre) with intensity
/// `weight`. Its length times its weight is its share of the shape's area.
struct RowSpan {
    int row;
    double left, right;
    double weight = 1.0;
};

/// A footprint that scanline spreading can write: rows of spans.
class RowProfile {
public:
    virtual ~RowProfile() = default;
    /// The spans of a pixel of CoC radius r, and their total weighted
    /// length (the shape's area).
    virtual double rows(double r, std::vector<RowSpan>& spans) const = 0;
    /// How far spans reach from the pixel, horizontally and vertically.
    virtual int reach() const = 0;
};

/// A convex aperture outline with the area of a disc of radius 1, scaled
/// to each pixel's CoC radius: a disc of radius r, or a polygon (rounded,
/// rotated, squeezed) of area πr². Radii below half a pixel use half a
/// pixel, so an in-focus pixel stays within itself. Rows are precomputed at
/// 1/16-pixel steps of radius and interpolated linearly between them, so
/// the footprint changes continuously with the radius; the tables are
/// built up front and shared by all threads.
class ApertureProfile final : public RowProfile {
public:
    ApertureProfile(const Aperture& aperture, double max_radius);

    /// The rows of a pixel of CoC radius r (clamped to the max radius), and
    /// their total length (the area, ≥ π/4).
    double rows(double r, std::vector<RowSpan>& spans) const override;
    int reach() const override { return m_reach; }

private:
    struct Table {
        int first_row;
        std::vector<double> centre, length;  // per row
    };
    Table build(double r) const;
    bool chord(double y, double& left, double& right) const;  ///< of the unit shape

    std::vector<double> m_left, m_right;  ///< unit chord at m_ymin + i * m_ystep
    double m_ymin, m_ystep;
    double m_max_radius;
    int m_reach;
    std::vector<Table> m_tables;  ///< at radius k / 16
};

/// An aperture shape taken from an image (`--aperture mask:FILE`): its
/// luminance thresholded at half its maximum, centred on its centroid,
/// scaled to the area of the CoC disc and squeezed by `aspect`. Any shape,
/// holes and all: each footprint row is the mask's runs at four sub-rows,
/// each a quarter of the row, and the spans of the two nearest 1/16-pixel
/// radii are blended, so the size changes continuously.
class MaskProfile final : public RowProfile {
public:
    /// False with `error` naming the file and the problem.
    bool load(const std::string& filename, double aspect, double max_radius,
              std::string& error);

    double rows(double r, std::vector<RowSpan>& spans) const override;
    int reach() const override { return m_reach; }

private:
    void spans_at(double r, double weight, std::vector<RowSpan>& spans) const;

    struct Run {
        int begin, end;  ///< mask columns [begin, end)
    };
    std::vector<std::vector<Run>> m_runs;  ///< per mask row
    double m_cx = 0, m_cy = 0;             ///< centroid, mask pixels
    double m_sx = 1, m_sy = 1;             ///< unit-shape units per mask pixel
    double m_max_radius = 0.5;
    int m_reach = 1;
};

/// The direct-reference PSF of a profile: each pixel weighted by the
/// overlap of the same row spans with it.
Psf aperture_psf(std::shared_ptr<const RowProfile> profile);

}  // namespace defocus
