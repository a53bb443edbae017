// Internal: compositing per part of the aperture (sub-aperture compositing).
//
// Blurring each layer and compositing the blurred layers with "over" gives
//     Σ_l ⟨C_l⟩ · Π_{m nearer} (1 − ⟨α_m⟩),
// the average ⟨·⟩ being over the aperture; the thin lens gives
//     ⟨ Σ_l C_l(x + c_l·u) · Π_{m nearer} (1 − α_m(x + c_m·u)) ⟩
// over aperture points u, c the signed CoC radius. They differ where a
// nearer layer's alpha varies over what a farther layer's light crosses: a
// near branch cuts its shadow into the bokeh of a far light. Cutting the
// aperture into cells k of shares w_k, compositing the layers within each
// cell and adding the cells converges to the second.
//
// The sum over cells is itself a stack of layers: layer l's light that
// reaches the camera is E_l = Σ_k w_k C_l^k Π_{m>l} (1 − α_m^k), and what
// passes through the layers from l to the front is
// T_l = Σ_k w_k Π_{m≥l} (1 − α_m^k). Layer l as one sample of colour
// E_l / T_{l+1} and alpha 1 − T_l / T_{l+1} gives, composited with "over",
// exactly the sum over cells. So each layer's spread keeps its place in
// every compositing that follows (a holdout between layers, a deep result's
// one sample per layer), and only its value changes, by
//     Δ_l = (E_l / T_{l+1}, 1 − T_l / T_{l+1}) − (its spread through the
//           whole aperture),
// added to its spread where "over" composites it (the alpha kept within
// [0, 1]), whatever it is composited onto.
//
// The engine spreads each layer whole, with every filter and lens effect;
// the cells are spread as rectangles only in the tiles where the plan
// (spread/cell_plan.h) says they change anything, and Δ_l is taken from
// those same rectangles, so that it is nothing where cells change nothing,
// and one cell leaves the engine's frame as it was.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include <Imath/half.h>
#include <OpenImageIO/imagebuf.h>

#include <defocus/composite/defocus_layers.h>
#include <defocus/layers/layered_scene.h>
#include <defocus/optics/camera.h>
#include <defocus/spread/aperture_profile.h>
#include <defocus/spread/cateye.h>

#include "spread/cell_plan.h"

namespace defocus {

struct BandSums;

/// Whether spreading `scene` as `spread` says composites per cell of the
/// aperture: not with one cell, nor with the soft PSFs of tent and smooth,
/// nor for a layer alone (nothing in front of it hides anything).
bool takes_aperture_cells(const SpreadOptions& spread, const LayeredScene& scene);

/// What compositing per cell of the aperture changes in each layer's
/// spread: made from the layers before they are spread (and freed), and
/// applied to each as it is composited.
class SubApertureLayers {
public:
    /// The changes over `window` for the layers of `scene` through `coc`
    /// of the colours of `channel`, with the aperture's shape `profile`,
    /// clipped by the barrel as `cateye` says; `cells` is the setting (0
    /// automatic, 1 none, else about that many). With `grown`, the window
    /// grows to take in wherever the layers' light lands.
    void compute(const LayeredScene& scene, const CircleOfConfusion& coc, CocChannel channel,
                 std::shared_ptr<const RowProfile> profile, const CatEye& cateye, int cells,
                 const OIIO::ROI& window, bool grown, int nthreads);

    /// Layer `l`'s change at pixel (x, y), RGBA, and the next pixels' of
    /// its row up to column `end`, into `out` (room for a tile's row);
    /// false where it has none, up to `end`.
    bool change(size_t l, int x, int y, int& end, float* out) const;
    /// visit(x, end, change) for the runs of row y that cover [x_begin,
    /// x_end): `change` is layer `l`'s over [x, end), RGBA a pixel, or null
    /// where it has none.
    template<typename Visit>
    void each_run(size_t l, int y, int x_begin, int x_end, Visit&& visit) const
    {
        float out[CellTiles::size * 4];
        for (int x = x_begin, end = x_end; x < x_end; x = end) {
            const bool changed = change(l, x, y, end, out);
            end = std::min(end, x_end);
            visit(x, end, changed ? out : nullptr);
        }
    }
    /// Whether layer `l` has a change anywhere.
    bool changes(size_t l) const;

    SubApertureReport report() const;

    /// What a layer's change holds a pixel.
    static constexpr size_t change_bytes = 4 * sizeof(Imath::half);
    /// The cells are found a window at a time, at most this many tile rows
    /// and columns.
    static constexpr int window_rows = 2, window_columns = 8;

private:
    static constexpr size_t tile_floats = size_t(CellTiles::size) * CellTiles::size * 4;

    /// Room for each layer's change in each tile with cells that its light
    /// reaches.
    void allocate(const std::vector<SignedLayer>& layers, int nthreads);
    /// Keeps the changes `sums` found over its band in tile (column, row);
    /// over blocks of `scale` pixels, read between them from `changes`
    /// (BandSums::all_changes).
    void keep(const BandSums& sums, int scale, int column, int row,
              const std::vector<float>& changes);
    /// keep() of tile `t` (pixels `tile`) from changes over blocks: each
    /// pixel's read between the four blocks' centres around it.
    void keep_between_blocks(const BandSums& sums, int scale, size_t t, const OIIO::ROI& tile,
                             const std::vector<float>& changes);
    /// Keeps a tile's changes (tile_floats, row by row) at `at` in
    /// m_pixels.
    void store(int64_t at, const float* changes);
    /// Where tile t's pixels for layer l start in m_pixels, or -1.
    int64_t offset(size_t l, size_t t) const { return m_offset[l][t]; }

    CellTiles m_tiles;
    std::vector<std::vector<int64_t>> m_offset;  ///< per layer, per tile
    /// RGBA, CellTiles::size² a tile and layer. In half: a change is a
    /// correction to the layer's spread, and half holds it to 1e-3 of
    /// itself, for half the memory (140 MB on the 4K example).
    std::unique_ptr<Imath::half[]> m_pixels;
    /// Per tile and layer, what its halves are multiplied by when read (see
    /// store()): 1 unless its changes are beyond half's range.
    std::vector<float> m_unscale;
    int m_most_cells = 0;
    int64_t m_tiles_over_blocks = 0;
};

}  // namespace defocus
