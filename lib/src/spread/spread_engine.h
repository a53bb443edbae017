// Internal: the one driver of the scattering filters (box, exact and
// bounded-time shapes).
//
// Output rows are made top to bottom in bands, one band per task, and each
// band in column tiles, left to right. A row is a sum of deltas that one
// prefix sum along x integrates (Kosloff, Tao & Barsky 2009); the box's
// corner deltas are first integrated down the columns (Heckbert 1986).
//
// Two paths feed a row's deltas:
//  - dense: single pixels of small footprint are scattered, source row by
//    source row, into a short ring of rows that the tile's width keeps in
//    cache;
//  - sparse: pixels of large footprint are summed in blocks of s x s
//    pixels (s = 2, 4, ... 32), each block spread once, and gathered into
//    a row just before it is integrated. Blocks of up to 4 (from r = 4 s)
//    spread the footprint of a uniform block (every pixel's shape on its
//    own centre, summed), so a uniform area comes out as exact spreading
//    makes it; larger ones wait until r = 8 s, and from 16 spread a
//    slightly softened shape from their centre (see level_start). Light
//    varying within a block is spread as if even over it, which under
//    such blurs is invisible except on highlights, whose bokeh shows its
//    outline, so those are spread exactly, on their own (the paper's
//    hybrid idea: the exact shape only where it shows).
//    Blocks of 4 and larger are spread on a half-resolution grid (blocks
//    half as wide, the shape at half the radius) whose integrated rows are
//    interpolated into the rows (see first_half_level): they cost a
//    quarter of the deltas and of the sums.
//    Radii near a change of block size are spread both ways, blended, so
//    footprints change continuously.
// The work per pixel is bounded whatever the blur. Rows are handed to a
// sink as they are made, so that compositing needs no layer-sized buffer.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <defocus/spread/cateye.h>

#include "spread/footprint_program.h"

namespace defocus {

/// Receives spread rows. Every row of the window that the spread reaches
/// comes once, in column pieces, each as row() or, where no light falls,
/// as dark(); concurrently, but never twice for one pixel.
class RowSink {
public:
    virtual ~RowSink() = default;
    /// Row y over columns [x_begin, x_end): premultiplied RGBA, 4 doubles
    /// per pixel.
    virtual void row(int y, int x_begin, int x_end, const double* rgba) = 0;
    /// Row y over columns [x_begin, x_end) is black. Skipped by default:
    /// most sinks add.
    virtual void dark(int /*y*/, int /*x_begin*/, int /*x_end*/) {}
    /// row() of pixels held as floats, `nc` channels a pixel (the first
    /// four are RGBA; fewer leave the rest 0), widened to doubles.
    void float_row(int y, int x_begin, int x_end, const float* values, int nc)
    {
        std::vector<double> rgba(size_t(std::max(0, x_end - x_begin)) * 4, 0.0);
        for (size_t x = 0; x < rgba.size() / 4; ++x)
            for (int c = 0; c < std::min(nc, 4); ++c)
                rgba[x * 4 + c] = values[x * size_t(nc) + c];
        row(y, x_begin, x_end, rgba.data());
    }
};

/// A layer's spread, handed to a sink a row at a time as it is made, so
/// that compositing needs no layer-sized buffer: the engine's, and tent's
/// and smooth's (SmoothRows).
class RowSpread {
public:
    virtual ~RowSpread() = default;
    /// Every pixel the spread can light.
    virtual const OIIO::ROI& extent() const = 0;
    /// Spreads into the sink the rows of `window` (within the extent).
    /// Light from pixels outside it still counts where it falls inside.
    virtual void run(const OIIO::ROI& window, RowSink& sink, int nthreads) const = 0;
};

/// The footprints of one aperture shape, for single pixels and for merged
/// blocks of every size, built as spreading needs them and shared by all
/// layers of a frame. With a cat's eye, each pixel or block takes the shape
/// clipped at the cell of its centre (ClippedProfile), one family of
/// footprints per cell and size, made the first time it is asked for.
class ShapePrograms {
public:
    ShapePrograms(std::shared_ptr<const RowProfile> profile, double max_radius,
                  const CatEye& cateye = {});
    ~ShapePrograms();

    /// Single pixels: where a footprint of a radius reaches (of the
    /// unclipped shape, which bounds every clipped one), and which program
    /// a radius takes (in every family of single pixels alike).
    const ProgramFamily& pixels() const { return *m_families.front(); }
    /// The same for uniform blocks of 2^level x 2^level pixels (see
    /// ProgramFamily).
    const ProgramFamily& blocks(int level) const { return *m_families[level]; }

    bool clipped() const { return m_cateye.amount > 0.0; }
    const CatEye& cateye() const { return m_cateye; }
    /// The footprints of blocks of 2^level pixels (as blocks()) clipped at
    /// `cell`; thread-safe.
    const ProgramFamily& clipped_blocks(int level, const CatEyeCell& cell) const;

private:
    std::shared_ptr<const RowProfile> m_profile;  ///< with a cat's eye, its sizes remembered
    double m_max_radius;
    CatEye m_cateye;
    std::vector<std::unique_ptr<ProgramFamily>> m_families;
    mutable std::mutex m_mutex;
    mutable std::unordered_map<int64_t, std::unique_ptr<ProgramFamily>> m_clipped;
};

/// The footprints of the pixels or blocks of one size by their centre
/// (ShapePrograms::clipped_blocks, remembering the last cell: neighbours
/// mostly share it).
class FamilyFinder {
public:
    /// `side`: CatEye::side of the layer spread.
    FamilyFinder(const ShapePrograms& shape, int level, double side)
        : m_shape(shape)
        , m_cateye(shape.cateye())
        , m_level(level)
        , m_family(&shape.blocks(level))
    {
        m_cateye.side = side;
    }

    /// For a pixel (block 1) or block of `block` pixels of CoC radius r
    /// centred at (x, y), full-resolution pixel coordinates.
    const ProgramFamily* at(double x, double y, int block, double r)
    {
        if (!m_shape.clipped())
            return m_family;
        const CatEyeCell cell = cateye_cell(m_cateye, Imath::V2d(x, y),
                                            cateye_fineness(block, r));
        if (!m_found || cell != m_cell) {
            m_family = &m_shape.clipped_blocks(m_level, cell);
            m_cell = cell;
            m_found = true;
        }
        return m_family;
    }

private:
    const ShapePrograms& m_shape;
    CatEye m_cateye;
    int m_level;
    const ProgramFamily* m_family;
    CatEyeCell m_cell { 0, 0, 0 };
    bool m_found = false;
};

/// A layer to spread: premultiplied RGBA and CoC radius over `roi`.
struct SpreadSource {
    OIIO::ROI roi;
    const float* color = nullptr;   ///< 4 floats per pixel, rows of roi.width()
    const float* radius = nullptr;  ///< 1 float per pixel
    /// Optional, 1 byte per pixel: pixels never merged into blocks
    /// (highlights whose bokeh is visible, see visible_bokeh).
    const uint8_t* keep_exact = nullptr;
    /// The box's rectangles: width over height, of the CoC disc's area.
    double box_aspect = 1.0;
    double cateye_side = 1.0;  ///< CatEye::side of the layer
};

/// The smallest CoC radius the Bounded method merges into blocks: below
/// it every pixel is spread exactly, so no highlight needs marking.
double smallest_merged_radius();

enum class SpreadMethod {
    Box,      ///< squares of the CoC disc's area, constant time (16 deltas)
    Exact,    ///< the shape, every pixel on its own: time grows with the radius
    Bounded,  ///< the shape, large footprints merged in blocks: bounded time
};

struct Tile;

class SpreadEngine final : public RowSpread {
public:
    /// `shape` is needed (and must outlive the engine) unless the method is
    /// Box.
    SpreadEngine(const SpreadSource& source, SpreadMethod method, const ShapePrograms* shape,
                 int nthreads);
    ~SpreadEngine();

    const OIIO::ROI& extent() const override { return m_extent; }
    void run(const OIIO::ROI& window, RowSink& sink, int nthreads) const override;

    struct Sparse;

private:
    struct Band;
    struct Workspace;

    void spread_band(const Band& band, Workspace& ws, RowSink& sink) const;
    void spread_box_tile(const Band& band, const Tile& tile, Workspace& ws, RowSink& sink) const;
    void spread_shape_tile(const Band& band, const Tile& tile, Workspace& ws,
                           RowSink& sink) const;
    void spread_carry_tile(const Band& band, const Tile& tile, const Tile& half_tile,
                           Workspace& ws, RowSink& sink) const;
    template<typename Visit>
    void visit_item_rows(const Band& band, const Tile& tile, const Tile& half_tile,
                         const Workspace& ws, Visit&& visit) const;

    struct Dense {
        float max_radius = -1.0f;  ///< of the pixels on this path; < 0: none
        int first_row = 0, last_row = 0, first_column = 0, last_column = 0;
        std::vector<uint8_t> rows;  ///< per source row: any pixel on this path
    };

    SpreadSource m_source;
    SpreadMethod m_method;
    const ShapePrograms* m_shape;
    Dense m_dense;
    std::vector<std::unique_ptr<Sparse>> m_sparse;  ///< per level: highlights, then blocks
    OIIO::ROI m_extent;
};

}  // namespace defocus
