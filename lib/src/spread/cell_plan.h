// Internal: where a frame is composited per part of the aperture, and in how
// many parts. Compositing the layers once per cell of the aperture changes
// the result only where a nearer layer's alpha varies over what a farther
// layer's light crosses; elsewhere the single composite is already exact.
#pragma once

#include <cstdint>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include "spread/cell_spread.h"

namespace defocus {

/// Square tiles over a window, each with the number of cells across the
/// aperture it is composited with: 0 for the single composite.
struct CellTiles {
    static constexpr int size = 32;  ///< pixels a side
    OIIO::ROI window;                ///< tiles start at its top left corner
    int columns = 0, rows = 0;
    std::vector<uint8_t> across;     ///< per tile, row by row

    uint8_t at(int column, int row) const { return across[size_t(row) * columns + column]; }
    /// The pixels of a tile, within the window.
    OIIO::ROI tile(int column, int row) const;
    int64_t count() const { return int64_t(columns) * rows; }
    int64_t with_cells() const;
};

/// The cells across the aperture in automatic mode for an occluder of CoC
/// radius `radius` whose shapes are `width` pixels wide (infinite: no
/// edge): enough that its footprint through one cell is no wider than its
/// shapes, nor than a tile. Fewer cells than that alias: they print a
/// coarse false shadow, further from the lens's than the whole aperture's
/// even dimming.
int automatic_cells_across(double radius, double width);

/// The tiles of `window` that `layers` (back to front) need cells in: where
/// a layer's alpha changes within the reach of its blur (its light through
/// each part of the lens covers different pixels) over a place a farther
/// layer lights. `cells` is the setting: 0 automatic, else about that many
/// cells (a grid of ⌈√cells⌉ across); 1 marks none.
CellTiles plan_cell_tiles(const std::vector<SignedLayer>& layers, const OIIO::ROI& window,
                          int cells, int nthreads);

}  // namespace defocus
