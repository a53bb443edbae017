// Internal: the spreading kernels that add a row's footprints to a tile
// and integrate it (compiled for each SIMD level, see util/simd.h).
#pragma once

#include <vector>

#include "spread/footprint_program.h"
#include "spread/item_rows.h"
#include "spread/spread_engine.h"
#include "spread/tile.h"

namespace defocus {

/// The dense pixels of source row `sy` within [x0, x1), as runs of
/// consecutive pixels on one program of `shape`.
void prepare_dense_row(const SpreadSource& src, SpreadMethod method, const ShapePrograms& shape,
                       int sy, int x0, int x1, ItemRow& row, std::vector<double>& color,
                       std::vector<float>& blend);

/// The box's 16 corner deltas (Kosloff, Tao & Barsky 2009, sec. 3, with
/// fractional edges), to be integrated down the columns and then along
/// the rows. Deltas above the tile go straight into the column carry.
void scatter_box_row(const SpreadSource& src, int sy, int x0, int x1, double* rows,
                     double* column_carry, const Tile& tile);

/// Adds the footprints of one row of items (pixels or blocks 2^shift
/// columns apart, anchored on row `anchor`) to the tile's delta rows: the
/// items' reach is `reach` (of the largest of the programs they use).
void scatter_items(int shift, const Reach& reach, const ItemRow& items, int anchor,
                   double* rows, const Tile& tile);

/// Integrates a tile row along x in place (after adding it to the column
/// carry, for the box), starting from the row carry, which it updates.
void finish_row(double* row, double* column_carry, double* row_carry, int cells);

/// Adds to cells [x_begin, x_end) of a row (`row` at x_begin) the
/// integrated half-resolution rows h0 and h1 below it, bilinearly
/// interpolated: h1 of weight wy, their cells from half-resolution column
/// `first` on. With `constant`, the row is that value, unset before.
void add_interpolated(double* row, const double* h0, const double* h1, double wy, int x_begin,
                      int x_end, int first, const double* constant);

}  // namespace defocus
