// An aperture shape as rows of intervals: what scanline spreading writes.
#pragma once

#include <memory>
#include <vector>

#include <defocus/aperture.h>
#include <defocus/footprint.h>

namespace defocus {

/// One row of a footprint: offset `row` from the pixel, covering
/// [left, right] (pixel units, relative to the pixel centre). Its length is
/// the shape's area within that row.
struct RowSpan {
    int row;
    double left, right;
};

/// A convex aperture outline with the area of a disc of radius 1, scaled
/// to each pixel's CoC radius: a disc of radius r, or a polygon (rounded,
/// rotated, squeezed) of area πr². Radii below half a pixel use half a
/// pixel, so an in-focus pixel stays within itself. Rows are precomputed at
/// 1/16-pixel steps of radius and interpolated linearly between them, so
/// the footprint changes continuously with the radius; the tables are
/// built up front and shared by all threads.
class ApertureProfile {
public:
    ApertureProfile(const Aperture& aperture, double max_radius);

    /// The rows of a pixel of CoC radius r (clamped to the max radius), and
    /// their total length (the area, ≥ π/4).
    double rows(double r, std::vector<RowSpan>& spans) const;

    /// How far rows reach from the pixel, horizontally and vertically.
    int reach() const { return m_reach; }

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

/// The direct-reference PSF of an aperture: each pixel weighted by the
/// overlap of the same row spans with it.
Psf aperture_psf(std::shared_ptr<const ApertureProfile> profile);

}  // namespace defocus
