#include "spread/aperture_cells.h"

#include <algorithm>
#include <cmath>

namespace defocus {

namespace {

/// The shape's rows are sampled this finely per cell of the grid.
constexpr int rows_per_cell = 64;

/// The area of a shape within one cell of the grid, and the area-weighted
/// sums of its rows' ends and centres there.
struct GridCellSums {
    double area = 0.0, left = 0.0, right = 0.0, centre = 0.0;
};

/// The sums of `shape` in each cell of the `across` × `across` grid over
/// the bounding square of its extent, row after row of the grid.
std::vector<GridCellSums> grid_sums(const RowProfile& shape, int across)
{
    const double radius = double(rows_per_cell) * across / (2.0 * shape.extent());
    std::vector<RowSpan> spans;
    shape.rows(radius, spans);
    const double edge = shape.extent(), side = 2.0 * edge / across;
    std::vector<GridCellSums> sums(size_t(across) * across);
    for (const RowSpan& span : spans) {
        // The grid row whose [v0, v1) holds the span, by the same sums
        // that give the cells' edges.
        const double v = span.row / radius;
        int j = std::clamp(int(std::floor((v + edge) / side)), 0, across - 1);
        while (j > 0 && v < -edge + j * side)
            --j;
        while (j + 1 < across && v >= -edge + j * side + side)
            ++j;
        const double v0 = -edge + j * side;
        if (v < v0 || v >= v0 + side)
            continue;
        for (int i = 0; i < across; ++i) {
            const double u0 = -edge + i * side, u1 = u0 + side;
            const double l = std::max(u0, span.left / radius),
                         r = std::min(u1, span.right / radius);
            if (r <= l)
                continue;
            const double a = (r - l) * span.weight / radius;
            GridCellSums& s = sums[size_t(j) * across + i];
            s.area += a;
            s.left += l * a;
            s.right += r * a;
            s.centre += v * a;
        }
    }
    return sums;
}

}  // namespace

std::vector<ApertureCell> cut_aperture(const RowProfile& profile, int across)
{
    across = std::max(1, across);
    const std::vector<GridCellSums> sums = grid_sums(profile, across);
    std::vector<ApertureCell> cells;
    double total = 0.0;
    for (size_t g = 0; g < sums.size(); ++g) {
        const GridCellSums& s = sums[g];
        if (s.area <= 0.0)
            continue;
        const double left = s.left / s.area, right = s.right / s.area, centre = s.centre / s.area;
        const double half_height = 0.5 * s.area / (right - left);
        cells.push_back(
            { left, right, centre - half_height, centre + half_height, s.area, int(g) });
        total += s.area;
    }
    for (ApertureCell& cell : cells)
        cell.weight /= total;
    return cells;
}

std::vector<double> clipped_shares(const RowProfile& clipped,
                                   const std::vector<ApertureCell>& cells, int across)
{
    const std::vector<GridCellSums> sums = grid_sums(clipped, std::max(1, across));
    std::vector<double> shares(cells.size());
    double total = 0.0;
    for (size_t k = 0; k < cells.size(); ++k)
        total += shares[k] = sums[size_t(cells[k].grid)].area;
    for (size_t k = 0; k < cells.size(); ++k)
        shares[k] = total > 0.0 ? shares[k] / total : cells[k].weight;
    return shares;
}

}  // namespace defocus
