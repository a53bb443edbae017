// Internal: which pixels are spread alone and which in blocks, and how
// far their footprints reach. See spread_engine.h for the method.
#pragma once

#include <array>

#include <defocus/spread/footprint.h>

#include "spread/footprint_program.h"
#include "spread/spread_engine.h"
#include "util/simd.h"

namespace defocus {

constexpr int max_level = 5;               ///< blocks of up to 32 x 32 pixels
constexpr double transition = 1.0 / 16.0;  ///< relative radius range spread at two sizes

/// The radius from which blocks of s = 2^level pixels take over (shared
/// with the level below just before it). Blocks up to max_box pixels wide
/// spread a uniform block's exact footprint, which keeps the fidelity bars
/// from r = 4 s. Larger ones wait until r = 8 s: they average light over
/// more pixels, and from 16 pixels (wider than max_box on the
/// half-resolution grid too) they spread the shape from their centre,
/// moving light by up to s / 2.
constexpr double level_start(int level)
{
    return ((1 << level) <= max_box ? 4.0 : 8.0) * (1 << level);
}

constexpr bool level_starts_are_powers_of_two()
{
    for (int level = 0; level <= max_level; ++level) {
        const long start = long(level_start(level));
        if (double(start) != level_start(level) || (start & (start - 1)) != 0)
            return false;
    }
    return true;
}
// So r times 1 / level_start() is r over it, bit for bit, without a
// division (components()).
static_assert(level_starts_are_powers_of_two(), "inverse_level_starts() must stay exact");

/// 1 / level_start(level) for every level.
constexpr std::array<double, max_level + 1> inverse_level_starts()
{
    std::array<double, max_level + 1> inverse {};
    for (int level = 0; level <= max_level; ++level)
        inverse[size_t(level)] = 1.0 / level_start(level);
    return inverse;
}

/// The largest radius a bounded spread takes on the dense path: where
/// blocks of 2 pixels take over.
constexpr float dense_limit = float(level_start(1));
/// Blocks from this level on (4 pixels and up, from radius 15) are spread
/// at half resolution, as blocks half as wide in pixels twice as large,
/// with the shape at half the radius, and the result is interpolated back
/// (bilinearly). A block of 4 already spreads its pixels' light as if even
/// over the block, so the half-resolution grid loses nothing it kept, and
/// under a blur of 15 pixels or more the interpolation's softening of a
/// footprint's edge is invisible (on the garden scene within 0.003 dB),
/// while the deltas and the sums that integrate them drop fourfold.
constexpr int first_half_level = 2;

inline bool is_zero(const float* v)
{
    return v[0] == 0.0f && v[1] == 0.0f && v[2] == 0.0f && v[3] == 0.0f;
}

/// a / 2^shift, rounded down (GCC shifts negative numbers arithmetically).
DEFOCUS_KERNEL int floor_shift(int a, int shift)
{
    return a >> shift;
}

inline int floor_div(int a, int b)  // b > 0
{
    return a >= 0 ? a / b : -((-a + b - 1) / b);
}

/// Level 0 is a single pixel; level L > 0 a block of 2^L pixels.
struct Component {
    int level;
    float weight;
};

/// The levels a pixel is spread at, and their shares. Level L > 0 takes
/// radii from level_start(L); just below that, radii are shared between
/// levels L - 1 and L, so that footprints change continuously.
inline int components(SpreadMethod method, float r, bool keep_exact, Component out[2])
{
    if (method != SpreadMethod::Bounded || !(r >= smallest_merged_radius()) || keep_exact) {
        out[0] = { 0, 1.0f };
        return 1;
    }
    static constexpr std::array<double, max_level + 1> inverse_start = inverse_level_starts();
    int level = 1;
    while (level < max_level && r * inverse_start[level + 1] >= 1.0 - transition)
        ++level;
    const double u = (r * inverse_start[level] - (1.0 - transition)) / transition;
    if (u <= 0.0) {  // where the transition starts: the smaller size alone
        out[0] = { level - 1, 1.0f };
        return 1;
    }
    if (u < 1.0) {
        out[0] = { level - 1, float(1.0 - u) };
        out[1] = { level, float(u) };
        return 2;
    }
    out[0] = { level, 1.0f };
    return 1;
}

/// How far footprints' deltas reach: rows and columns relative to their
/// anchor pixel.
struct Reach {
    int first_row, last_row, first_column, last_column;
};

inline Reach box_reach(float max_radius, double aspect)
{
    const BoxHalfWidths h = box_half_widths(max_radius, aspect);
    const BoxEdges ex = box_edges(h.x), ey = box_edges(h.y);
    return { ey.first, ey.last + 1, ex.first, ex.last + 1 };
}

inline Reach program_reach(const FootprintProgram& p)
{
    return { p.first_row(), p.last_row(), p.first_column(), p.last_column() };
}

}  // namespace defocus
