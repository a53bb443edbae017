// Internal: a layer's light through one cell of the aperture, over a band of
// rows: each pixel's footprint through the cell is a rectangle, written as
// corner deltas and integrated (Kosloff, Tao & Barsky 2009), so
// that the cost does not grow with the blur.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include "spread/aperture_cells.h"

namespace defocus {

/// Whether `roi` holds a pixel. Not npixels(): that multiplies a negative
/// width by a negative height, as an intersection of apart windows has.
inline bool has_pixels(const OIIO::ROI& roi)
{
    return roi.width() > 0 && roi.height() > 0;
}

/// A CoC radius below this is no blur: every part of the lens sees the
/// same, and every cell of it lets the same through.
constexpr float sharp_radius = 0.5f;

/// Lit pixels of one row and one signed radius, columns [x_begin, x_end),
/// and the radius's mean slope over them (see SignedLayer).
struct PixelRun {
    int x_begin, x_end;
    float radius;
    float slope[2] = { 0.0f, 0.0f };  ///< ∂ρ/∂x, ∂ρ/∂y a pixel
};

/// A layer as sub-aperture spreading reads it: premultiplied RGBA of each
/// pixel of `roi` (rows of roi.width()), and its lit pixels as runs of one
/// signed CoC radius (negative in front of the focus), row by row.
///
/// Where the radius changes along a surface, the pixels' footprints through
/// one part of the lens crowd or spread apart: through aperture point u,
/// pixel s lands at s + ρ(s)·u, which scales area by 1 + u·∇ρ. Spreading
/// keeps each pixel's light, so a tilted opaque surface would come out
/// denser than opaque through one side of the lens and see-through on the
/// other, and "over" per cell would cut seams into it; each pixel's light
/// through a cell is weighted by that scale instead, with its run's mean
/// ∇ρ (a run's pixels lie within 1/8 pixel of radius on one surface), which
/// leaves the whole aperture's light as it was.
struct SignedLayer {
    OIIO::ROI roi;
    const float* color = nullptr;    ///< 4 floats a pixel
    std::vector<PixelRun> runs;      ///< row by row, left to right
    std::vector<size_t> row_runs;    ///< row y's runs start at row_runs[y - roi.ybegin]; one past
    float extent = 1.0f;             ///< how far the aperture reaches per unit of radius
    float radii[2] = { 0.0f, 0.0f }; ///< the lowest and highest signed radius lit
    OIIO::ROI lit;                   ///< the bounds of the lit pixels (undefined: none)

    /// How far any pixel's light lands from it.
    float reach() const { return std::max(std::abs(radii[0]), std::abs(radii[1])) * extent; }
    /// The pixels this layer's light can land on (undefined: none).
    OIIO::ROI light() const;
    /// The pixels of `window` that this layer's light can land on; none
    /// (see has_pixels) where it lands on none of them.
    OIIO::ROI light_in(const OIIO::ROI& window) const;
    /// The pixels whose light can land in `window`, were they lit.
    OIIO::ROI sources_of(const OIIO::ROI& window) const;
    /// For each pixel of `window` (row by row), 1 where every pixel whose
    /// light can land on it is lit, opaque and on one surface with its
    /// neighbours (no step in depth): through every part of the lens the
    /// layer covers it, and whatever lies behind is hidden.
    void solid_in(const OIIO::ROI& window, std::vector<uint8_t>& solid) const;

    /// `roi`'s pixels of colour `color` and signed radius `radius` (a float
    /// a pixel), as runs.
    void set(const OIIO::ROI& roi, const float* color, const float* radius, float extent,
             int nthreads);
};

/// The light of layers through a cell over a window of pixels, in double:
/// spread() adds a layer's footprints as corner deltas, and integrate()
/// turns them into each row's light, leaving the band clear for the next.
class CellBand {
public:
    /// Sets the window, clear.
    void reset(const OIIO::ROI& window);

    const OIIO::ROI& window() const { return m_window; }

    /// Adds the light of `layer`'s pixels through `cell` that falls in the
    /// window: each pixel's light is spread evenly over its footprint
    /// through the cell, so that it keeps its sum.
    void spread(const SignedLayer& layer, const ApertureCell& cell);

    /// Calls use(y, x_begin, x_end, light) for each row y of the window
    /// where the last spread layer's light lands, top to bottom: light is
    /// premultiplied RGBA, 4 doubles a pixel from the window's first column,
    /// and holds that row's light over columns [x_begin, x_end) (the window's
    /// coordinates); elsewhere the light is nothing. Then the band is clear.
    template<typename Use>
    void integrate(Use&& use)
    {
        if (!has_pixels(m_box))
            return;
        const int first = m_box.xbegin - m_window.xbegin;
        std::fill(m_running.begin() + ptrdiff_t(first) * 4,
                  m_running.begin() + ptrdiff_t(first + m_box.width() + 2) * 4, 0.0);
        for (int y = m_box.ybegin; y < m_box.yend; ++y)
            use(y, m_box.xbegin, m_box.xend, integrate_row(y - m_window.ybegin));
        const int end = m_box.yend - m_window.ybegin;
        clear_rows(end, std::min(end + 2, m_window.height() + 2));
    }

private:
    const double* integrate_row(int row);
    void clear_rows(int first, int end);

    OIIO::ROI m_window;
    OIIO::ROI m_box;                ///< where the last spread layer's light lands
    size_t m_stride = 0;            ///< doubles a row: 4 a pixel, two past the window's end
    std::vector<double> m_deltas;   ///< rows of the window and two past its end
    std::vector<double> m_running;  ///< the deltas summed down the columns so far
    std::vector<double> m_row;      ///< a row's light
    std::vector<double> m_line;     ///< a run's pixels, then their light filtered along its row
};

}  // namespace defocus
