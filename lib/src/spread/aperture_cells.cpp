#include "spread/aperture_cells.h"

#include <algorithm>
#include <cmath>

namespace defocus {

namespace {

/// The shape's rows are sampled this finely per cell of the grid.
constexpr int rows_per_cell = 64;

}  // namespace

std::vector<ApertureCell> cut_aperture(const RowProfile& profile, int across)
{
    across = std::max(1, across);
    const double radius = double(rows_per_cell) * across / (2.0 * profile.extent());
    std::vector<RowSpan> spans;
    profile.rows(radius, spans);
    const double edge = profile.extent(), side = 2.0 * edge / across;
    std::vector<ApertureCell> cells;
    for (int j = 0; j < across; ++j) {
        const double v0 = -edge + j * side, v1 = v0 + side;
        for (int i = 0; i < across; ++i) {
            const double u0 = -edge + i * side, u1 = u0 + side;
            // The area of the shape within the cell, and the area-weighted
            // sums of its rows' ends and centres.
            double area = 0.0, left = 0.0, right = 0.0, centre = 0.0;
            for (const RowSpan& span : spans) {
                const double v = span.row / radius;
                const double l = std::max(u0, span.left / radius),
                             r = std::min(u1, span.right / radius);
                if (v < v0 || v >= v1 || r <= l)
                    continue;
                const double a = (r - l) * span.weight / radius;
                area += a;
                left += l * a;
                right += r * a;
                centre += v * a;
            }
            if (area <= 0.0)
                continue;
            left /= area;
            right /= area;
            centre /= area;
            const double half_height = 0.5 * area / (right - left);
            cells.push_back({ left, right, centre - half_height, centre + half_height, area });
        }
    }
    double total = 0.0;
    for (const ApertureCell& cell : cells)
        total += cell.weight;
    for (ApertureCell& cell : cells)
        cell.weight /= total;
    return cells;
}

}  // namespace defocus
