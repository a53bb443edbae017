// Internal: an aperture shape's footprints as row deltas, ready to spread.
//
// Scanline spreading (Kosloff, Tao & Barsky 2009, sec. 4.1) writes each row
// of a footprint as edge deltas that one prefix sum along x turns into the
// row's interval. A program holds those deltas for two neighbouring sizes
// of the shape at once, each delta with a weight per size, so that a pixel
// between two tabulated radii spreads the blend of both and its footprint
// grows continuously with its radius.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include <defocus/spread/aperture_profile.h>
#include <defocus/spread/footprint.h>

namespace defocus {

/// Deltas at `taps` adjacent columns of a footprint row, from `column`
/// relative to the anchor pixel: an edge of a row's interval, split over
/// the columns it falls between. Their weights for the smaller and for the
/// larger size are taps values each from index `at` of the program's
/// weight arrays.
struct DeltaCluster {
    int32_t column, taps, at;
};

/// The row deltas of a footprint blended between two sizes, by row offset
/// from the anchor pixel. Each size's deltas sum to zero along every row
/// and their row intervals have total weight 1.
class FootprintProgram {
public:
    /// From a pixel's spans at both sizes: the footprint of a uniform
    /// square of `box` x `box` pixels (1: the pixel alone; else even, its
    /// centre on the anchor pixel's lower right corner), each pixel's shape
    /// on its own centre: the shape convolved with the box.
    FootprintProgram(const std::vector<RowSpan>& smaller, double smaller_area,
                     const std::vector<RowSpan>& larger, double larger_area, int box);

    int first_row() const { return m_first_row; }
    int last_row() const { return m_first_row + int(m_row_begin.size()) - 2; }
    int first_column() const { return m_first_column; }
    int last_column() const { return m_last_column; }

    /// The clusters of row offset `row`, first_row() <= row <= last_row().
    const DeltaCluster* begin(int row) const { return m_clusters.data() + m_row_begin[row - m_first_row]; }
    const DeltaCluster* end(int row) const { return m_clusters.data() + m_row_begin[row - m_first_row + 1]; }
    /// Weights for the smaller and for the larger size.
    const double* smaller() const { return m_smaller.data(); }
    const double* larger() const { return m_larger.data(); }

    /// The footprint of weight 1 - t on the smaller size and t on the larger
    /// one, as a weight table: what spreading writes, for the direct
    /// reference.
    Footprint footprint(double t) const;

private:
    int m_first_row = 0, m_first_column = 0, m_last_column = 0;
    std::vector<uint32_t> m_row_begin;  ///< per row, and one past the last
    std::vector<DeltaCluster> m_clusters;
    std::vector<double> m_smaller, m_larger;
};

/// Programs are tabulated every quarter of a pixel of radius, or of a
/// block's width for merged blocks: blending the two nearest sizes then
/// softens a footprint's edge by at most a quarter pixel, which on the
/// garden scene matches path-traced bokeh better than finer bins do.
constexpr double radius_bins_per_pixel = 4.0;

/// Blocks up to this many pixels wide spread a uniform block's exact
/// footprint. Larger ones spread a uniform 2 x 2 square around their
/// centre: an exact edge would be a block wide and cost more deltas than
/// merging saves.
constexpr int max_box = 4;

/// Which program a radius uses, and how much of its larger size.
struct ProgramBlend {
    int k;
    float t;
};

/// The programs of one shape at one centring, for every radius up to a
/// largest one: program k blends radii k and k + 1 times `bin_width` (at
/// least half a pixel, so that an in-focus pixel covers exactly itself;
/// larger radii take the largest). Programs are built the first time they
/// are asked for; that is thread-safe.
class ProgramFamily {
public:
    /// Programs for blocks of `block` x `block` pixels (1: single pixels),
    /// anchored on pixel block / 2 - 1 of the block in each direction.
    ProgramFamily(std::shared_ptr<const RowProfile> profile, int block, double bin_width,
                  double max_radius);
    ~ProgramFamily();

    ProgramBlend pick(double radius) const
    {
        const double x = std::min(m_max_bin, std::max(m_min_bin, radius * m_bins_per_pixel));
        const int k = std::min(int(x), int(m_built.size()) - 1);
        return { k, float(x - k) };
    }
    const FootprintProgram& program(int k) const
    {
        if (const FootprintProgram* p = m_built[k].load(std::memory_order_acquire))
            return *p;
        return build(k);
    }

private:
    const FootprintProgram& build(int k) const;

    std::shared_ptr<const RowProfile> m_profile;
    int m_block;
    double m_bin_width, m_bins_per_pixel, m_min_bin, m_max_bin;
    mutable std::mutex m_mutex;
    mutable std::vector<std::atomic<const FootprintProgram*>> m_built;  ///< per program
    mutable std::vector<std::unique_ptr<FootprintProgram>> m_owned;
};

}  // namespace defocus
