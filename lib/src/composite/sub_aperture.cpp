#include "composite/sub_aperture.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <map>
#include <tuple>

#include "spread/aperture_cells.h"
#include "spread/coarse_layers.h"
#include "util/float_pixels.h"
#include "util/fresh_array.h"
#include "util/parallel_rows.h"
#include "util/simd.h"

namespace defocus {

using namespace OIIO;

/// How a layer stands at a pixel of a band: see-through from some part of
/// the lens; solid (SignedLayer::solid_in); or hidden behind a nearer
/// layer solid there.
enum class Cover : uint8_t { Open, Solid, Hidden };

namespace {

/// A layer's pixels as the cells spread them, with their signed radii in
/// the colours of `channel`.
void make_source(const Layer& layer, const CircleOfConfusion& coc, CocChannel channel,
                 double extent, FloatPixels& color, SignedLayer& signed_layer, int nthreads)
{
    ROI roi = roi_intersection(layer.color.roi(), layer.depth.roi());
    roi.chbegin = 0;
    roi.chend = 4;
    color = FloatPixels(layer.color, roi);
    ROI depth_roi = roi;
    depth_roi.chend = layer.depth.nchannels();
    const FloatPixels depth(layer.depth, depth_roi);
    const std::unique_ptr<float[]> radius = fresh_array<float>(size_t(roi.npixels()), nthreads);
    parallel_for(roi.ybegin, roi.yend, [&](int64_t y) {
        for (int x = roi.xbegin; x < roi.xend; ++x)
            radius[size_t(y - roi.ybegin) * roi.width() + (x - roi.xbegin)]
                = float(0.5 * coc.diameter(*depth(x, int(y)), x, int(y), channel));
    }, by_rows(nthreads));
    signed_layer.set(roi, roi.npixels() > 0 ? color(roi.xbegin, roi.ybegin) : nullptr,
                     radius.get(), float(extent), nthreads);
}

/// Whether `layer`'s light can reach `window`.
bool reaches(const SignedLayer& layer, const ROI& window)
{
    return has_pixels(layer.light_in(window));
}

/// One layer's row of light through a cell, taken front to back, the
/// cell's share of the lens at pixel x being weight[x * step] (a step of 0:
/// the same everywhere): adds it to the layer's light through the whole
/// aperture, adds what of it reaches the camera (`reaching`: RGB, and in the 4th lane the
/// share of the lens that the layers in front let through), and lets
/// `passing` (what the layers in front let through) through this one.
/// Where the layer is solid (SignedLayer::solid_in), it covers the pixel
/// through every part of the lens, and its light is taken as covering it
/// whole: its runs are cut where the quantized radius steps, and through a
/// cell the footprints on either side of a step move apart or together by
/// the step times the cell's offset, leaving the pixel a little under or
/// over covered; a light behind would show through the gap. Elsewhere "over"
/// takes it as the engine composites: where a layer's own pixels overlap
/// past full coverage, scaled back to it. Where a nearer layer is solid,
/// the layer is hidden through every part of the lens, and nothing of it
/// is taken: its change there is nothing, whatever its sums.
DEFOCUS_CLONES
void take_row(const double* light, const Cover* cover, const double* weight, size_t step,
              float* whole, float* reaching, double* passing, int pixels)
{
    for (int x = 0; x < pixels; ++x) {
        if (cover[x] == Cover::Hidden)
            continue;
        const double share = weight[size_t(x) * step];
        const d4 raw = load4(light + x * 4);
        store4(whole + x * 4, load4(whole + x * 4) + splat(share) * raw);
        const double a = raw[3];
        const bool whole_cover = cover[x] == Cover::Solid && a > 0.0;
        d4 seen = whole_cover || a > 1.0 ? raw * splat(1.0 / a) : raw;
        const double alpha = whole_cover ? 1.0 : std::clamp(a, 0.0, 1.0);
        seen.v[3] = 1.0;
        store4(reaching + x * 4, load4(reaching + x * 4) + splat(share * passing[x]) * seen);
        passing[x] *= 1.0 - alpha;
    }
}

}  // namespace

/// The cells' shares of the lens as the barrel clips it (the cat's eye)
/// over a band: physically the clip is of the lens, at the pixel the light
/// reaches, the same for every layer; the clip's offset is taken on
/// cateye_cell's grid, and each offset's shares are found once.
class ClippedShares {
public:
    ClippedShares(std::shared_ptr<const RowProfile> aperture, const CatEye& cateye)
        : m_aperture(std::move(aperture))
        , m_cateye(cateye)
    {
    }

    /// Each pixel of `band`'s shares of `cells` (cut `across`), the band
    /// being over blocks of `scale` pixels from (x0, y0), or pixels.
    void over(const ROI& band, int scale, int x0, int y0, const std::vector<ApertureCell>& cells,
              int across, std::vector<const double*>& out)
    {
        out.resize(size_t(band.npixels()));
        size_t p = 0;
        for (int y = band.ybegin; y < band.yend; ++y)
            for (int x = band.xbegin; x < band.xend; ++x, ++p) {
                const Imath::V2d centre = scale == 1 ? Imath::V2d(x + 0.5, y + 0.5)
                                                     : Imath::V2d(x0 + (x + 0.5) * scale,
                                                                  y0 + (y + 0.5) * scale);
                const CatEyeCell at = cateye_cell(m_cateye, centre);
                std::vector<double>& shares = m_found[{ across, at.x, at.y }];
                if (shares.empty())
                    shares = clipped_shares(ClippedProfile(m_aperture, cateye_cell_offset(at),
                                                           m_cateye.clip_aspect),
                                            cells, across);
                out[p] = shares.data();
            }
    }

private:
    std::shared_ptr<const RowProfile> m_aperture;
    CatEye m_cateye;
    std::map<std::tuple<int, int, int>, std::vector<double>> m_found;
};

/// Tiles of a band that one cut of the aperture composites together: rows
/// [first_row, end_row), columns [first_column, last_column], spread over
/// blocks of `scale` pixels.
struct CellWindow {
    int across;
    int first_row, end_row, first_column, last_column;
    int scale;

    /// How many of its tiles take its cut.
    int64_t tiles(const CellTiles& all) const
    {
        int64_t n = 0;
        for (int row = first_row; row < end_row; ++row)
            for (int column = first_column; column <= last_column; ++column)
                n += all.at(column, row) == across;
        return n;
    }
    /// Its pixels.
    ROI pixels(const CellTiles& tiles) const
    {
        return roi_union(tiles.tile(first_column, first_row), tiles.tile(last_column, end_row - 1));
    }
    /// What it is spread over: its pixels, or its blocks and one more all
    /// round, between whose centres its pixels are read.
    ROI spread(const CellTiles& tiles) const
    {
        if (scale == 1)
            return pixels(tiles);
        const ROI blocks = blocks_of(pixels(tiles), scale, tiles.window.xbegin,
                                     tiles.window.ybegin);
        return ROI(blocks.xbegin - 1, blocks.xend + 1, blocks.ybegin - 1, blocks.yend + 1);
    }
};

/// The windows that the cuts of the aperture (`cuts`, by cells across)
/// composite `tiles` in, band of tile rows by band, each spread over the
/// coarsest blocks its `layers` allow (`extent`: how far the aperture
/// reaches at unit radius).
std::vector<std::vector<CellWindow>> plan_windows(
    const CellTiles& tiles, const std::map<int, std::vector<ApertureCell>>& cuts,
    const std::vector<SignedLayer>& layers, double extent)
{
    // Bands of two tile rows: a pixel's light reaches the bands of the
    // rows its blur spans, so taller bands would spread each pixel fewer
    // times, but their buffers fall out of the caches (4 rows took 6%
    // longer on the 4K example, 8 rows 40%). A band is cut into windows
    // where its tiles with cells are far enough apart that no pixel's light
    // reaches both sides, and every 8 tiles: each cell reads its layers'
    // pixels around the window again, and 256 columns of them stay in the
    // core's cache (the 4K example's spread stage took 12% longer in
    // windows as wide as the frame).
    float reach = 0.0f;
    for (const SignedLayer& layer : layers)
        reach = std::max(reach, layer.reach());
    const int gap = int(std::ceil(2.0 * reach / CellTiles::size)) + 1;
    std::vector<RadiusTiles> radii;
    for (const SignedLayer& layer : layers)
        radii.emplace_back(layer, CellTiles::size, tiles.window.xbegin, tiles.window.ybegin);
    const int window_rows = SubApertureLayers::window_rows,
              window_columns = SubApertureLayers::window_columns;
    std::vector<std::vector<CellWindow>> bands(size_t(tiles.rows + window_rows - 1) / window_rows);
    for (size_t b = 0; b < bands.size(); ++b) {
        const int first_row = int(b) * window_rows,
                  end_row = std::min(tiles.rows, first_row + window_rows);
        for (const auto& [across, cut] : cuts) {
            auto used_in = [&, across = across](int column) {
                for (int row = first_row; row < end_row; ++row)
                    if (tiles.at(column, row) == across)
                        return true;
                return false;
            };
            for (int first = 0; first < tiles.columns;) {
                if (!used_in(first)) {
                    ++first;
                    continue;
                }
                int last = first;
                for (int column = first + 1; column < tiles.columns && column <= last + gap
                                             && column < first + window_columns;
                     ++column)
                    if (used_in(column))
                        last = column;
                CellWindow window { across, first_row, end_row, first, last, 1 };
                window.scale = coarsest_scale(layers, radii, window.pixels(tiles),
                                              2.0 * extent / across);
                bands[b].push_back(window);
                first = last + 1;
            }
        }
    }
    return bands;
}

/// Where the cells change a band, layer by layer: for each layer that
/// reaches it (back to front), its light through the whole aperture and
/// what of it reaches the camera; and what passes through every layer.
///
/// A layer's sums are made only over its light's box: outside it, its
/// light is nothing and it lets everything through, so what passes through
/// it and the layers in front is what passes through those in front.
struct BandSums {
    ROI band;
    std::vector<size_t> layers;   ///< the layers that reach the band, back to front
    std::vector<ROI> boxes;       ///< per layer, where its light lands in the band
    std::vector<float> whole;     ///< RGBA a pixel, per layer
    std::vector<float> reaching;  ///< E_l (RGB) and T_{l+1} a pixel, per layer, in its box
    std::vector<double> passing;  ///< through the layers so far, this cell
    std::vector<double> through;  ///< T_0: through every layer, all cells
    std::vector<std::vector<Cover>> cover;  ///< per layer, over the band

    /// The sums over `pixels` through `cells`, each pixel's shares of
    /// them `clipped[p]` where the barrel clips the lens (else their
    /// weights).
    void sum(const std::vector<SignedLayer>& all, const std::vector<ApertureCell>& cells,
             const std::vector<const double*>* clipped, const ROI& pixels, CellBand& spread);

    /// Layer i's (of `layers`) change at pixel (x, y) of the band.
    void change(size_t i, int x, int y, float* out) const;
    /// Every layer's change over the band: RGBA a pixel, layer after layer.
    void all_changes(std::vector<float>& out) const;

private:
    /// T_{i+1} at (x, y), pixel p: what passes through the layers in
    /// front of layer i (of `layers`); i = -1 for all of them.
    double in_front(ptrdiff_t i, int x, int y, size_t p) const;
};

void BandSums::sum(const std::vector<SignedLayer>& all, const std::vector<ApertureCell>& cells,
                   const std::vector<const double*>* clipped, const ROI& pixels,
                   CellBand& spread)
{
    band = pixels;
    layers.clear();
    boxes.clear();
    for (size_t l = 0; l < all.size(); ++l)
        if (const ROI box = all[l].light_in(band); has_pixels(box)) {
            layers.push_back(l);
            boxes.push_back(box);
        }
    // Where a layer is solid, it hides those behind it through every part
    // of the lens. Where the layers in front hide the whole band, those
    // behind are not spread, and their sums stay nothing, as does their
    // change.
    const size_t n = size_t(band.npixels()), row = size_t(band.width());
    size_t first_seen = 0;
    cover.resize(layers.size());
    std::vector<uint8_t> hidden(n, 0), solid;
    for (size_t i = layers.size(); i-- > 0;) {
        if (std::all_of(hidden.begin(), hidden.end(), [](uint8_t h) { return h != 0; })) {
            first_seen = i + 1;
            break;
        }
        all[layers[i]].solid_in(band, solid);
        cover[i].resize(n);
        for (size_t p = 0; p < n; ++p) {
            cover[i][p] = hidden[p] ? Cover::Hidden : solid[p] ? Cover::Solid : Cover::Open;
            hidden[p] |= solid[p];
        }
    }
    for (size_t i = 0; i < first_seen; ++i)
        cover[i].assign(n, Cover::Hidden);
    whole.assign(layers.size() * n * 4, 0.0f);
    reaching.assign(layers.size() * n * 4, 0.0f);
    passing.assign(n, 1.0);
    through.assign(n, 0.0);
    spread.reset(band);
    std::vector<double> shares(clipped ? n : 0);
    const size_t step = clipped ? 1 : 0;
    for (size_t k = 0; k < cells.size(); ++k) {
        const ApertureCell& cell = cells[k];
        if (clipped)
            for (size_t p = 0; p < n; ++p)
                shares[p] = (*clipped)[p][k];
        const double* weight = clipped ? shares.data() : &cell.weight;
        for (size_t i = layers.size(); i-- > first_seen;) {
            spread.spread(all[layers[i]], cell);
            spread.integrate([&](int y, int x_begin, int x_end, const double* light) {
                const size_t first = size_t(x_begin - band.xbegin);
                const size_t at = size_t(y - band.ybegin) * row + first;
                take_row(light + first * 4, &cover[i][at], weight + at * step, step,
                         &whole[(i * n + at) * 4], &reaching[(i * n + at) * 4], &passing[at],
                         x_end - x_begin);
            });
        }
        for (size_t p = 0; p < n; ++p) {
            through[p] += weight[p * step] * passing[p];
            passing[p] = 1.0;
        }
    }
}

double BandSums::in_front(ptrdiff_t i, int x, int y, size_t p) const
{
    for (; i >= 0; --i)
        if (boxes[size_t(i)].contains(x, y))
            return reaching[(size_t(i) * passing.size() + p) * 4 + 3];
    return through[p];
}

void BandSums::change(size_t i, int x, int y, float* out) const
{
    const size_t n = passing.size();
    const size_t p = size_t(y - band.ybegin) * size_t(band.width()) + size_t(x - band.xbegin);
    if (!boxes[i].contains(x, y)) {
        std::fill(out, out + 4, 0.0f);
        return;
    }
    const float* w = &whole[(i * n + p) * 4];
    const float* e = &reaching[(i * n + p) * 4];
    const double front = e[3];
    const double back = in_front(ptrdiff_t(i) - 1, x, y, p);
    // Where the layers in front hide it from the whole lens, the layer's
    // light counts for nothing, whatever its colour.
    if (front <= 1e-12) {
        std::fill(out, out + 4, 0.0f);
        return;
    }
    // Where the layer is solid, its light through the whole lens covers the
    // pixel whole as it does through each cell: the engine's spread of the
    // surface does, and only the cells' difference from it is a change.
    const double a = w[3];
    const bool whole_cover = cover[i][p] == Cover::Solid && a > 0.0;
    const double scale = a > 1.0 || whole_cover ? 1.0 / a : 1.0;
    for (int c = 0; c < 3; ++c)
        out[c] = float(e[c] / front - w[c] * scale);
    out[3] = float((1.0 - back / front) - (whole_cover ? 1.0 : std::clamp(a, 0.0, 1.0)));
}

void BandSums::all_changes(std::vector<float>& out) const
{
    out.resize(layers.size() * passing.size() * 4);
    float* at = out.data();
    for (size_t i = 0; i < layers.size(); ++i)
        for (int y = band.ybegin; y < band.yend; ++y)
            for (int x = band.xbegin; x < band.xend; ++x, at += 4)
                change(i, x, y, at);
}

bool takes_aperture_cells(const SpreadOptions& spread, const LayeredScene& scene)
{
    return spread.aperture_cells != 1 && spread.aperture.shape != ApertureShape::Tent
           && spread.aperture.shape != ApertureShape::Smooth && lit_layers(scene).size() > 1;
}

void SubApertureLayers::compute(const LayeredScene& scene, const CircleOfConfusion& coc,
                                CocChannel channel, std::shared_ptr<const RowProfile> profile,
                                const CatEye& cateye,
                                int cells, const ROI& window, bool grown, int nthreads)
{
    std::vector<FloatPixels> colors(scene.layers.size());
    std::vector<SignedLayer> layers(scene.layers.size());
    for (size_t l = 0; l < scene.layers.size(); ++l)
        if (scene.reports[l].pixels > 0)
            make_source(scene.layers[l], coc, channel, profile->extent(), colors[l], layers[l],
                        nthreads);
    ROI where = window;
    if (grown)
        for (const SignedLayer& layer : layers)
            if (const ROI light = layer.light(); light.defined())
                where = roi_union(where, light);
    m_tiles = plan_cell_tiles(layers, where, cells, nthreads);
    allocate(layers, nthreads);
    std::map<int, std::vector<ApertureCell>> cuts;
    for (uint8_t across : m_tiles.across)
        if (across > 1 && !cuts.count(across))
            cuts[across] = cut_aperture(*profile, across);
    m_most_cells = 0;
    for (const auto& [across, cut] : cuts)
        m_most_cells = std::max(m_most_cells, int(cut.size()));

    const std::vector<std::vector<CellWindow>> bands
        = plan_windows(m_tiles, cuts, layers, profile->extent());
    // The pixels of the windows spread over blocks, by blocks' size.
    ROI over_blocks[5];
    m_tiles_over_blocks = 0;
    for (const std::vector<CellWindow>& band : bands)
        for (const CellWindow& window : band)
            if (window.scale > 1) {
                ROI& all = over_blocks[window.scale];
                const ROI pixels = window.pixels(m_tiles);
                all = all.defined() ? roi_union(all, pixels) : pixels;
                m_tiles_over_blocks += window.tiles(m_tiles);
            }
    // The layers by blocks of 1, 2 and 4 pixels, as windows take them:
    // over blocks, only the pixels whose light reaches such a window.
    std::vector<SignedLayer> scaled[5];
    std::vector<std::vector<float>> block_colors;
    for (int scale : { 2, 4 })
        if (const ROI& all = over_blocks[scale]; all.defined())
            for (const SignedLayer& layer : layers)
                scaled[scale].push_back(coarse_layer(layer, layer.sources_of(all), scale,
                                                     m_tiles.window.xbegin, m_tiles.window.ybegin,
                                                     block_colors.emplace_back(), nthreads));
    scaled[1] = std::move(layers);
    const bool clips = cateye.amount != 0.0;
    parallel_for_each_item(0, int64_t(bands.size()), [&](int64_t b) {
        CellBand spread;
        BandSums sums;
        ClippedShares clip(profile, cateye);
        std::vector<const double*> shares;
        std::vector<float> changes;
        for (const CellWindow& window : bands[size_t(b)]) {
            const std::vector<ApertureCell>& cut = cuts.at(window.across);
            const ROI pixels = window.spread(m_tiles);
            if (clips)
                clip.over(pixels, window.scale, m_tiles.window.xbegin, m_tiles.window.ybegin, cut,
                          window.across, shares);
            sums.sum(scaled[window.scale], cut, clips ? &shares : nullptr, pixels, spread);
            if (window.scale > 1)
                sums.all_changes(changes);
            for (int row = window.first_row; row < window.end_row; ++row)
                for (int column = window.first_column; column <= window.last_column; ++column)
                    if (m_tiles.at(column, row) == window.across)
                        keep(sums, window.scale, column, row, changes);
        }
    }, nthreads);
}

void SubApertureLayers::allocate(const std::vector<SignedLayer>& layers, int nthreads)
{
    const size_t tiles = size_t(m_tiles.count());
    m_offset.assign(layers.size(), std::vector<int64_t>(tiles, -1));
    int64_t used = 0;
    for (size_t t = 0; t < tiles; ++t) {
        if (m_tiles.across[t] <= 1)
            continue;
        const ROI tile = m_tiles.tile(int(t % m_tiles.columns), int(t / m_tiles.columns));
        for (size_t l = 0; l < layers.size(); ++l)
            if (reaches(layers[l], tile))
                m_offset[l][t] = (used++) * int64_t(tile_floats);
    }
    // Left unset: keep() writes every pixel that change() reads.
    m_pixels = fresh_array<Imath::half>(size_t(used) * tile_floats, nthreads);
    m_unscale.assign(size_t(used), 1.0f);
}

void SubApertureLayers::store(int64_t at, const float* changes)
{
    // Half's largest is 65504: a change beyond it (a highlight in the
    // thousands, brightened by a footprint narrower than a pixel) would be
    // infinite, and "over" would turn it into NaN. Such a tile is kept
    // scaled down by a power of two, exact to half's precision.
    float largest = 0.0f;
    for (size_t i = 0; i < tile_floats; ++i)
        largest = std::max(largest, std::abs(changes[i]));
    constexpr float room = 32768.0f;
    const float scale = largest > room ? std::exp2(-std::ceil(std::log2(largest / room))) : 1.0f;
    m_unscale[size_t(at) / tile_floats] = 1.0f / scale;
    Imath::half* out = &m_pixels[size_t(at)];
    for (size_t i = 0; i < tile_floats; ++i)
        out[i] = changes[i] * scale;
}

void SubApertureLayers::keep(const BandSums& sums, int scale, int column, int row,
                             const std::vector<float>& changes)
{
    const size_t t = size_t(row) * m_tiles.columns + column;
    const ROI tile = m_tiles.tile(column, row);
    if (scale > 1) {
        keep_between_blocks(sums, scale, t, tile, changes);
        return;
    }
    std::vector<float> changes_in_tile(tile_floats);
    for (size_t i = 0; i < sums.layers.size(); ++i) {
        const int64_t at = offset(sums.layers[i], t);
        if (at < 0)
            continue;
        std::fill(changes_in_tile.begin(), changes_in_tile.end(), 0.0f);
        for (int y = tile.ybegin; y < tile.yend; ++y)
            for (int x = tile.xbegin; x < tile.xend; ++x)
                sums.change(i, x, y,
                            &changes_in_tile[((y - tile.ybegin) * CellTiles::size
                                              + (x - tile.xbegin)) * 4]);
        store(at, changes_in_tile.data());
    }
}

void SubApertureLayers::keep_between_blocks(const BandSums& sums, int scale, size_t t,
                                            const ROI& tile, const std::vector<float>& changes)
{
    const ROI& blocks = sums.band;
    const size_t per_layer = size_t(blocks.npixels()) * 4;
    // Each pixel's centre among the blocks' centres (at block + 1/2): the
    // block before it, and how far along to the next.
    struct Between {
        int block;
        float along;
    };
    auto between = [&](int x, int origin, int begin, int end) {
        const float b = (x + 0.5f - origin) / float(scale) - 0.5f;
        const int block = std::clamp(int(std::floor(b)), begin, end - 2);
        return Between { block, std::clamp(b - float(block), 0.0f, 1.0f) };
    };
    Between columns[CellTiles::size];
    for (int x = tile.xbegin; x < tile.xend; ++x)
        columns[x - tile.xbegin] = between(x, m_tiles.window.xbegin, blocks.xbegin, blocks.xend);
    const size_t row_floats = size_t(blocks.width()) * 4;
    std::vector<float> changes_in_tile(tile_floats);
    for (size_t l = 0; l < m_offset.size(); ++l) {
        const int64_t at = offset(l, t);
        if (at < 0)
            continue;
        std::fill(changes_in_tile.begin(), changes_in_tile.end(), 0.0f);
        const auto found = std::find(sums.layers.begin(), sums.layers.end(), l);
        if (found == sums.layers.end()) {
            store(at, changes_in_tile.data());
            continue;
        }
        const float* layer = &changes[size_t(found - sums.layers.begin()) * per_layer];
        float* row = changes_in_tile.data();
        for (int y = tile.ybegin; y < tile.yend; ++y, row += CellTiles::size * 4) {
            const Between down = between(y, m_tiles.window.ybegin, blocks.ybegin, blocks.yend);
            const float* top = layer + size_t(down.block - blocks.ybegin) * row_floats;
            const float* bottom = top + row_floats;
            for (int i = 0; i < tile.width(); ++i) {
                const Between& across = columns[i];
                const size_t b = size_t(across.block - blocks.xbegin) * 4;
                const float fx = across.along, fy = down.along;
                const float w00 = (1.0f - fx) * (1.0f - fy), w10 = fx * (1.0f - fy),
                            w01 = (1.0f - fx) * fy, w11 = fx * fy;
                for (int k = 0; k < 4; ++k)
                    row[i * 4 + k] = w00 * top[b + k] + w10 * top[b + 4 + k]
                                     + w01 * bottom[b + k] + w11 * bottom[b + 4 + k];
            }
        }
        store(at, changes_in_tile.data());
    }
}

bool SubApertureLayers::change(size_t l, int x, int y, int& end, float* out) const
{
    const ROI& window = m_tiles.window;
    if (l >= m_offset.size() || y < window.ybegin || y >= window.yend || x >= window.xend) {
        end = INT_MAX;
        return false;
    }
    if (x < window.xbegin) {
        end = window.xbegin;
        return false;
    }
    const int column = (x - window.xbegin) / CellTiles::size,
              row = (y - window.ybegin) / CellTiles::size;
    const ROI tile = m_tiles.tile(column, row);
    end = tile.xend;
    const int64_t at = offset(l, size_t(row) * m_tiles.columns + column);
    if (at < 0)
        return false;
    const Imath::half* in
        = &m_pixels[size_t(at) + ((y - tile.ybegin) * CellTiles::size + (x - tile.xbegin)) * 4];
    std::copy(in, in + size_t(end - x) * 4, out);
    if (const float unscale = m_unscale[size_t(at) / tile_floats]; unscale != 1.0f)
        for (size_t i = 0; i < size_t(end - x) * 4; ++i)
            out[i] *= unscale;
    return true;
}

bool SubApertureLayers::changes(size_t l) const
{
    return l < m_offset.size()
           && std::any_of(m_offset[l].begin(), m_offset[l].end(), [](int64_t at) { return at >= 0; });
}

SubApertureReport SubApertureLayers::report() const
{
    return { m_tiles.count(), m_tiles.with_cells(), m_most_cells, m_tiles_over_blocks };
}

}  // namespace defocus
