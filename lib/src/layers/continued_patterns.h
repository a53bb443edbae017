// Internal: the surface behind a hole, copied from where the pixels on its
// two sides repeat along its row or column (exemplar-based filling,
// Criminisi, Perez & Toyama 2004, restricted to one line of search).
#pragma once

#include <vector>

#include <OpenImageIO/imagebuf.h>

#include "layers/hole_map.h"
#include "util/float_pixels.h"

namespace defocus {

/// For each hidden pixel of a layer in a hole, the surface behind it
/// copied from the same row (for a hole's run along a row) or column,
/// shifted to where the pixels beside the run, on both sides and on the
/// rows (columns) next to it, look most alike: a checker, bricks or
/// stripes behind a pole or a card continue with their period, which a line
/// between the hole's two sides blurs into a blotch. Across a wide run,
/// sides that match on one line may match by chance (arcs of a curved
/// surface match a different shift on every row, and copies would cut
/// them into streaks), so a run wider than `widest_lone_run` is trusted
/// only as far as the runs on the lines beside it copy from the same
/// shift, as a pattern that repeats along the line does. A copy holds no colour
/// its sides do not (a light from afar). Copies come only from
/// seen pixels of the layer (not those continued behind a nearer edge) no
/// nearer than the run's sides. Each value
/// is premultiplied R, G, B, A and the alpha-weighted depth.
class ContinuedPatterns {
public:
    /// `holes` flags the hidden pixels of `color`'s ROI; runs up to
    /// `max_width` long are continued for those within `window`.
    ContinuedPatterns(const FloatPixels& color, const FloatPixels& depth, const HoleMap& holes,
                      const OIIO::ROI& window, int max_width, int nthreads);

    /// How far from a hidden pixel the search reads.
    static int reach(int max_width);

    /// The copied surface at hidden pixel (x, y) and how much to trust it
    /// (1 where the pixels beside the run match their copy's exactly,
    /// falling as they differ against the texture's own variation); false
    /// where no copy was found or the sides are plain.
    bool at(int x, int y, float value[5], float& trust) const;

private:
    struct Copy {
        int dx = 0, dy = 0;
        float trust = 0.0f;  ///< 0: none found
    };
    /// A run's copy: pixels [begin, end) along its line.
    struct CopiedRun {
        int begin, end;
        Copy copy;
    };

    struct Run;
    struct Sample;
    struct ColourRange;

    static void pixel(bool along_rows, int u, int v, int& x, int& y);
    void continue_runs(bool along_rows, std::vector<std::vector<CopiedRun>>& copied,
                       int nthreads);
    /// Each wide run's trust times the share of the lines beside it, of
    /// those with a run across it, that copy from the same shift.
    static void weigh_by_neighbours(bool along_rows, std::vector<std::vector<CopiedRun>>& copied,
                                    int nthreads);
    /// The copy of the run along line `v` of `copied` that holds `u`, or
    /// null.
    static const Copy* copy_at(const std::vector<std::vector<CopiedRun>>& copied, int first_line,
                               int v, int u);
    /// The best copy for `run`; false where none is, or its sides are
    /// plain.
    bool best_copy(bool along_rows, const Run& run, Copy& copy) const;
    std::vector<Sample> sides(bool along_rows, const Run& run, float& nearest) const;
    /// How unlike `sides` the pixels `shift` along the line are (infinite
    /// where the copy cannot be taken).
    float difference(bool along_rows, const Run& run, const std::vector<Sample>& sides,
                     const ColourRange& range, int shift, float nearest,
                     std::vector<float>& differences) const;
    void observation(int x, int y, float value[5]) const;
    bool observed(int x, int y) const;

    const FloatPixels& m_color;
    const FloatPixels& m_depth;
    const HoleMap& m_holes;
    OIIO::ROI m_window;
    int m_max_width;
    /// Per row and per column of the window, its runs' copies, in order.
    std::vector<std::vector<CopiedRun>> m_row_copies, m_column_copies;
};

}  // namespace defocus
