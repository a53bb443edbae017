// Internal: layers at a fraction of the resolution, for the cells of the
// aperture where every footprint through a cell is many pixels wide.
//
// Through a cell of width Δ (at unit radius) a pixel of radius ρ lights a
// rectangle |ρ|·Δ wide: the light of every layer through the cell is
// already a box blur that wide, and so is what it lets through. Where
// every layer that reaches a window blurs so by at least three blocks of
// s × s pixels, the cells are spread over blocks: s² times fewer pixels,
// and the change they make is read back between the blocks' centres (at
// two blocks, the thin bars of our lattice scene lost 0.2 dB at focus
// 1.5; at three no scene of ours moves). A layer in focus throughout lets
// the same through every cell, which divides out of every change: it sets
// no bound.
#pragma once

#include <vector>

#include <OpenImageIO/imagebuf.h>

#include "spread/cell_spread.h"

namespace defocus {

/// The blocks of `scale` × `scale` pixels from (`x0`, `y0`) that `pixels`
/// meets, in blocks (block (0, 0) starts at (x0, y0)).
OIIO::ROI blocks_of(const OIIO::ROI& pixels, int scale, int x0, int y0);

/// `fine` over the blocks of `scale` × `scale` pixels from (`x0`, `y0`)
/// (block (0, 0) starts there) that meet `within`: each block the mean of
/// its pixels' premultiplied colour, and the coverage-weighted mean of
/// their radius, in blocks. The blocks' colours are kept in `color`, which
/// the result points into.
SignedLayer coarse_layer(const SignedLayer& fine, const OIIO::ROI& within, int scale, int x0,
                         int y0, std::vector<float>& color, int nthreads);

/// The least and the most |radius| of a layer's lit pixels in each tile of
/// a grid of `size`-pixel tiles from (`x0`, `y0`).
class RadiusTiles {
public:
    RadiusTiles() = default;
    RadiusTiles(const SignedLayer& layer, int size, int x0, int y0);

    /// Over the tiles that `roi` meets: false where none of them is lit.
    bool range(const OIIO::ROI& roi, float& least, float& most) const;

private:
    int m_size = 1, m_x0 = 0, m_y0 = 0;
    OIIO::ROI m_tiles;  ///< in tiles from (x0, y0)
    std::vector<float> m_least, m_most;
};

/// The coarsest of 4, 2 and 1 pixels a block at which cells `cell_width`
/// wide (at unit radius: u1 - u0) may be spread over `window`: every layer
/// (with its `radii`) whose light reaches it blurs by at least three blocks
/// through a cell, or is in focus throughout.
int coarsest_scale(const std::vector<SignedLayer>& layers, const std::vector<RadiusTiles>& radii,
                   const OIIO::ROI& window, double cell_width);

}  // namespace defocus
