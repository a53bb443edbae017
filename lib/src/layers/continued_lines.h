// Internal: the surface behind a thin hole, continued along straight lines
// from the two sides of the hole.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include "layers/hole_map.h"
#include "util/float_pixels.h"

namespace defocus {

/// For each hidden pixel of a layer, the surface behind it continued
/// along the lattice lines that cross its hole within `max_length` pixels.
/// A line interpolates between its two observed ends; a line whose ends,
/// the ends' neighbours across it and the pixels beyond each end agree in
/// colour, coverage and depth (one surface, one stripe, running along the
/// line on both sides) outweighs the others, so that stripes, edges and
/// checkers continue through a thin occluder. Cost: one pass over the
/// hidden pixels per direction and side, and the work of a line once for
/// all the pixels on it. Each value is premultiplied R, G, B, A and the
/// alpha-weighted depth.
class ContinuedLines {
public:
    /// `holes` flags the hidden pixels of `color`'s ROI; lines are found
    /// for those within `window`.
    ContinuedLines(const FloatPixels& color, const FloatPixels& depth, const HoleMap& holes,
                   const OIIO::ROI& window,
                   int max_length, int nthreads);

    /// How far from a hidden pixel the lines read: the line, the pixels
    /// beyond its ends and the ends' neighbours.
    static int reach(int max_length);

    /// The continued surface at hidden pixel (x, y) and how much to trust
    /// it (1 where the best line's ends agree exactly, falling as they
    /// differ); false where no line crosses.
    bool at(int x, int y, float value[5], float& trust) const;

private:
    struct Estimate {
        float sum[5] = { 0, 0, 0, 0, 0 };
        float weight = 0.0f;
        float best = INFINITY;  ///< the least disagreement of a line so far
    };

    /// slot() of a hidden pixel in a hole too wide for any line.
    static constexpr uint32_t blocked = UINT32_MAX;

    std::vector<uint8_t> in_wide_holes(int limit, int nthreads) const;
    bool hidden(int x, int y) const { return m_holes(x, y); }
    /// Of a window pixel: its index in m_pixels + 1 where it is tracked,
    /// 0 where it is observed, `blocked` where it lies in a wide hole.
    uint32_t slot(int x, int y) const;
    void observation(int x, int y, float value[5]) const;
    float change_beyond(int x, int y, int dx, int dy, const float end[5]) const;
    float disagreement_of_line(int ax, int ay, int bx, int by, int dx, int dy) const;
    void add_lines(int dx, int dy, const std::vector<uint16_t>& forward,
                   const std::vector<uint16_t>& backward, std::vector<float>& line_disagreement,
                   int nthreads);
    void steps_to_observed(int dx, int dy, std::vector<uint16_t>& steps) const;

    const FloatPixels& m_color;
    const FloatPixels& m_depth;
    const HoleMap& m_holes;
    OIIO::ROI m_window;
    int m_max_length;
    struct Pixel {
        int x, y;
    };
    std::vector<Pixel> m_pixels;   ///< the tracked pixels of the window, in raster order
    /// Which window pixels are tracked, 64 to a word, m_words words a row
    /// (2 MB for a 4K frame, where a slot per pixel took 40 MB).
    int m_words;
    std::vector<uint64_t> m_tracked;
    std::vector<uint32_t> m_rank;  ///< per word: the tracked pixels before it
    std::vector<uint32_t> m_first;  ///< per window row: its first tracked pixel
    std::vector<Estimate> m_estimates;  ///< per hidden pixel
};

}  // namespace defocus
