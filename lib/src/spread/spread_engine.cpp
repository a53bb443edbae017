#include "spread/spread_engine.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <mutex>

#include <OpenImageIO/parallel.h>

#include <defocus/spread/footprint.h>

#include "spread/block_levels.h"
#include "spread/item_rows.h"
#include "spread/layer_survey.h"
#include "spread/scatter_rows.h"
#include "spread/tile.h"
#include "util/parallel_rows.h"
#include "util/simd.h"

namespace defocus {

using OIIO::ROI;

double smallest_merged_radius()
{
    return level_start(1) * (1.0 - transition);
}

namespace {

/// A shape's spans, each size made once: the clipped shapes of a cat's
/// eye's cells all cut the same sizes of the same aperture.
class RememberedProfile final : public RowProfile {
public:
    explicit RememberedProfile(std::shared_ptr<const RowProfile> profile)
        : m_profile(std::move(profile))
    {
    }

    double rows(double r, std::vector<RowSpan>& spans) const override
    {
        {
            std::lock_guard<std::mutex> lock(m_mutex);
            const auto found = m_sizes.find(r);
            if (found != m_sizes.end()) {
                spans = found->second.spans;
                return found->second.area;
            }
        }
        const double area = m_profile->rows(r, spans);
        std::lock_guard<std::mutex> lock(m_mutex);
        m_sizes.emplace(r, Size { area, spans });
        return area;
    }
    double extent() const override { return m_profile->extent(); }

private:
    struct Size {
        double area;
        std::vector<RowSpan> spans;
    };
    std::shared_ptr<const RowProfile> m_profile;
    mutable std::mutex m_mutex;
    mutable std::unordered_map<double, Size> m_sizes;
};

}  // namespace

ShapePrograms::ShapePrograms(std::shared_ptr<const RowProfile> profile, double max_radius,
                             const CatEye& cateye)
    : m_profile(cateye.amount > 0.0 ? std::make_shared<RememberedProfile>(std::move(profile))
                                    : std::move(profile))
    , m_max_radius(max_radius)
    , m_cateye(cateye)
{
    // Clipped shapes are cut in sub-rows: their uncut sub-rows bound them.
    const std::shared_ptr<const RowProfile> bound =
        clipped() ? std::make_shared<ClippedProfile>(m_profile, Imath::V2d(0.0, 0.0),
                                                     cateye.clip_aspect, false)
                  : m_profile;
    for (int level = 0; level <= max_level; ++level)
        m_families.push_back(std::make_unique<ProgramFamily>(
            bound, 1 << level, (1 << level) / radius_bins_per_pixel, max_radius));
}

ShapePrograms::~ShapePrograms() = default;

const ProgramFamily& ShapePrograms::clipped_blocks(int level, const CatEyeCell& cell) const
{
    // Cells lie within a few thousand of the origin (offsets of at most
    // the largest amount): 16 bits each.
    const int64_t key = (int64_t(level) << 40) | (int64_t(cell.fineness) << 32)
                        | (int64_t(uint16_t(cell.x)) << 16) | int64_t(uint16_t(cell.y));
    std::lock_guard<std::mutex> lock(m_mutex);
    std::unique_ptr<ProgramFamily>& family = m_clipped[key];
    if (!family)
        family = std::make_unique<ProgramFamily>(
            std::make_shared<ClippedProfile>(m_profile, cateye_cell_offset(cell),
                                             m_cateye.clip_aspect),
            1 << level,
            (1 << level) / radius_bins_per_pixel, m_max_radius);
    return *family;
}

SpreadEngine::SpreadEngine(const SpreadSource& source, SpreadMethod method,
                           const ShapePrograms* shape, int nthreads)
    : m_source(source)
    , m_method(method)
    , m_shape(shape)
{
    const ROI& roi = source.roi;
    // Every level a pixel might take, and the block rows it would fill.
    std::vector<std::unique_ptr<Sparse>> levels;
    LayerSurvey found;
    for (int l = 0; method != SpreadMethod::Box && l <= max_level; ++l) {
        auto level = std::make_unique<Sparse>();
        level->level = l;
        level->half = l >= first_half_level;
        level->family = l == 0 ? &shape->pixels() : &shape->blocks(level->grid_shift());
        level->first_block_row = floor_shift(roi.ybegin, l);
        found.block_rows.emplace_back(floor_shift(roi.yend - 1, l) - level->first_block_row + 1);
        levels.push_back(std::move(level));
    }
    found.sparse_max.assign(levels.size(), -1.0f);
    found.dense_rows.assign(size_t(roi.height()), 0);
    // One pass, in stripes of whole block rows of every level.
    const int stripe = 1 << max_level;
    const int first_stripe = floor_shift(roi.ybegin, max_level);
    const int stripes = floor_shift(roi.yend - 1, max_level) - first_stripe + 1;
    std::mutex merge;
    parallel_for_each_item(0, stripes, [&](int64_t i) {
        const int y0 = std::max(roi.ybegin, (first_stripe + int(i)) * stripe);
        const int y1 = std::min(roi.yend, (first_stripe + int(i) + 1) * stripe);
        survey_rows(source, method, shape, levels, y0, y1, found, merge);
    }, nthreads);
    m_dense.max_radius = found.dense_max;
    m_dense.rows = std::move(found.dense_rows);

    // The last column of a footprint's deltas (and for the box the last
    // row) only ends it: the pixels it lights stop one before. Interpolated
    // from half resolution, half-resolution pixel i lights pixels 2 i - 1
    // to 2 i + 2.
    auto grow = [&](const ROI& anchors, const Reach& reach, bool box, bool half) {
        ROI lit(anchors.xbegin + reach.first_column, anchors.xend + reach.last_column - 1,
                anchors.ybegin + reach.first_row, anchors.yend + reach.last_row - box, 0, 1, 0, 4);
        if (half)
            lit = ROI(2 * lit.xbegin - 1, 2 * lit.xend + 1, 2 * lit.ybegin - 1, 2 * lit.yend + 1,
                      0, 1, 0, 4);
        m_extent = m_extent.defined() ? OIIO::roi_union(m_extent, lit) : lit;
    };
    if (m_dense.max_radius >= 0.0f) {
        const Reach reach = method == SpreadMethod::Box
                                ? box_reach(m_dense.max_radius, source.box_aspect)
                                : program_reach(shape->pixels().program(
                                    shape->pixels().pick(m_dense.max_radius).k));
        m_dense.first_row = reach.first_row;
        m_dense.last_row = reach.last_row;
        m_dense.first_column = reach.first_column;
        m_dense.last_column = reach.last_column;
        grow(roi, reach, method == SpreadMethod::Box, false);
    }

    for (size_t l = 0; l < levels.size(); ++l) {
        if (found.sparse_max[l] < 0.0f)
            continue;
        std::unique_ptr<Sparse>& level = levels[l];
        level->rows = std::move(found.block_rows[l]);
        // Programs of larger radii reach at least as far.
        level->reach = program_reach(level->family->program(level->pick(found.sparse_max[l]).k));
        const int s = 1 << level->level;
        const int first = level->first_block_row, last = first + int(level->rows.size()) - 1;
        const ROI anchors(level->anchor(floor_div(roi.xbegin, s)),
                          level->anchor(floor_div(roi.xend - 1, s)) + 1, level->anchor(first),
                          level->anchor(last) + 1);
        grow(anchors, level->reach, false, level->half);
        m_sparse.push_back(std::move(level));
    }
    if (!m_extent.defined()) {  // nothing carries light: the region itself, dark
        m_extent = roi;
        m_extent.chbegin = 0;
        m_extent.chend = 4;
    }
}

SpreadEngine::~SpreadEngine() = default;

/// One band of output rows, as its tiles share it: the rows, the window's
/// columns, and the source rows and columns whose deltas can land in it.
struct SpreadEngine::Band {
    ROI window;
    int y_begin, y_end, tile_width;
    HalfSpan half_y;  ///< the half-resolution rows its rows interpolate
    bool half;        ///< any level spreads at half resolution
    int sy0, sy1, sx0, sx1;
};

/// What a band's thread keeps between tiles (and layers): reused, so that
/// its memory is touched once rather than once per layer.
struct SpreadEngine::Workspace {
    std::vector<ItemRow> dense;        ///< the band's dense source rows, prepared
    std::vector<double> color;         ///< scratch for preparing them
    std::vector<float> blend;
    std::vector<double> rows;          ///< the tile's delta rows
    std::vector<double> column_carry;  ///< the box's deltas integrated down the columns
    std::vector<double> row_carry;     ///< per band row, the sum left of the tile
    std::vector<double> half_rows;     ///< the same at half resolution
    std::vector<double> half_row_carry;
};

void SpreadEngine::run(const ROI& window_in, RowSink& sink, int nthreads) const
{
    const ROI window = OIIO::roi_intersection(window_in, m_extent);
    if (window.width() <= 0 || window.height() <= 0)
        return;
    const bool box = m_method == SpreadMethod::Box;
    const bool half = std::any_of(m_sparse.begin(), m_sparse.end(),
                                  [](const std::unique_ptr<Sparse>& level) { return level->half; });
    const ROI& roi = m_source.roi;
    const int box_rows = box ? m_dense.last_row - m_dense.first_row : 0;
    const int box_columns = box ? m_dense.last_column - m_dense.first_column : 0;
    const int band_rows = std::clamp(box_tile_reaches * box_rows, tile_rows, box_tile_limit);
    const int tile_width = std::clamp(box_tile_reaches * box_columns, tile_columns, box_tile_limit);
    const int bands = (window.height() + band_rows - 1) / band_rows;
    parallel_for_each_item(0, bands, [&](int64_t i) {
        thread_local Workspace ws;
        Band band;
        band.window = window;
        band.y_begin = window.ybegin + int(i) * band_rows;
        band.y_end = std::min(window.yend, band.y_begin + band_rows);
        band.tile_width = tile_width;
        band.half_y = half_span(band.y_begin, band.y_end);
        band.half = half;
        band.sy0 = std::max(roi.ybegin, band.y_begin - m_dense.last_row);
        band.sy1 = std::min(roi.yend, band.y_end - m_dense.first_row);
        band.sx0 = std::max(roi.xbegin, window.xbegin - m_dense.last_column);
        band.sx1 = std::min(roi.xend, window.xend - m_dense.first_column);
        spread_band(band, ws, sink);
    }, nthreads);
}

void SpreadEngine::spread_band(const Band& band, Workspace& ws, RowSink& sink) const
{
    const ROI& roi = m_source.roi;
    ws.row_carry.assign(size_t(band.y_end - band.y_begin) * 4, 0.0);
    if (band.half)
        ws.half_row_carry.assign(size_t(band.half_y.end - band.half_y.begin) * 4, 0.0);
    const bool box = m_method == SpreadMethod::Box;
    if (m_dense.max_radius >= 0.0f && !box) {
        if (ws.dense.size() < size_t(std::max(0, band.sy1 - band.sy0)))
            ws.dense.resize(band.sy1 - band.sy0);
        for (int sy = band.sy0; sy < band.sy1; ++sy) {
            if (m_dense.rows[size_t(sy - roi.ybegin)])
                prepare_dense_row(m_source, m_method, *m_shape, sy, band.sx0, band.sx1,
                                  ws.dense[sy - band.sy0], ws.color, ws.blend);
            else
                ws.dense[sy - band.sy0].clear();
        }
    }
    const ROI& window = band.window;
    for (int x_begin = window.xbegin; x_begin < window.xend; x_begin += band.tile_width) {
        const Tile tile { band.y_begin, band.y_end, x_begin,
                          std::min(window.xend, x_begin + band.tile_width),
                          x_begin == window.xbegin };
        if (box)
            spread_box_tile(band, tile, ws, sink);
        else
            spread_shape_tile(band, tile, ws, sink);
    }
}

void SpreadEngine::spread_box_tile(const Band& band, const Tile& tile, Workspace& ws,
                                   RowSink& sink) const
{
    // The box's deltas, integrated down the columns: scattered into the
    // whole tile first.
    const ROI& roi = m_source.roi;
    const size_t row_size = size_t(tile.cells()) * 4;
    ws.rows.assign(size_t(tile.y_end - tile.y_begin) * row_size, 0.0);
    ws.column_carry.assign(row_size, 0.0);
    const int x0 = std::max(roi.xbegin, tile.x_begin - m_dense.last_column);
    const int x1 = std::min(roi.xend, tile.x_end - m_dense.first_column);
    const bool dense = m_dense.max_radius >= 0.0f;
    for (int sy = band.sy0; sy < band.sy1 && dense && x0 < x1; ++sy)
        scatter_box_row(m_source, sy, x0, x1, ws.rows.data(), ws.column_carry.data(), tile);
    for (int y = tile.y_begin; y < tile.y_end; ++y) {
        double* row = ws.rows.data() + (y - tile.y_begin) * row_size;
        finish_row(row, ws.column_carry.data(), ws.row_carry.data() + size_t(y - tile.y_begin) * 4,
                   tile.cells());
        sink.row(y, tile.x_begin, tile.x_end, row + 4);
    }
}

/// Shapes: every source row and block row within reach of the tile (or of
/// its half-resolution twin) is visited, visit(shift, reach, items,
/// anchor, at_half), until visit returns false.
template<typename Visit>
void SpreadEngine::visit_item_rows(const Band& band, const Tile& tile, const Tile& half_tile,
                                   const Workspace& ws, Visit&& visit) const
{
    if (m_dense.max_radius >= 0.0f) {
        const Reach dense_reach { m_dense.first_row, m_dense.last_row, m_dense.first_column,
                                  m_dense.last_column };
        for (int sy = band.sy0; sy < band.sy1; ++sy)
            if (!visit(0, dense_reach, ws.dense[sy - band.sy0], sy, false))
                return;
    }
    for (const std::unique_ptr<Sparse>& level : m_sparse) {
        const Tile& t = level->half ? half_tile : tile;
        const int s = level->grid_block(), offset = s == 1 ? 0 : s / 2 - 1;
        const int first = level->first_block_row;
        const int lo = std::max(first, -floor_div(-(t.y_begin - level->reach.last_row - offset), s));
        const int hi = std::min(first + int(level->rows.size()) - 1,
                                floor_div(t.y_end - 1 - level->reach.first_row - offset, s));
        for (int b = lo; b <= hi; ++b)
            if (!visit(level->grid_shift(), level->reach, level->rows[b - first],
                       level->anchor(b), level->half))
                return;
    }
}

namespace {

/// Row y's half-resolution rows (from the tile's first), and the weight
/// of the lower one.
std::pair<int, double> half_rows_of(int y, const Tile& half_tile)
{
    return { floor_div(y - 1, 2) - half_tile.y_begin, upper_weight(y) };
}

/// Integrates the half-resolution tile's rows in place. The next tile's
/// half-resolution pixels start left of this one's end, at cell `carried`
/// (< 0: there is no next tile): its carry is the sum left of them.
void finish_half_rows(const Tile& half_tile, int carried, double* half_rows,
                      double* half_row_carry)
{
    const size_t half_row_size = size_t(half_tile.cells()) * 4;
    for (int j = half_tile.y_begin; j < half_tile.y_end; ++j) {
        double* row = half_rows + size_t(j - half_tile.y_begin) * half_row_size;
        double* carry = half_row_carry + size_t(j - half_tile.y_begin) * 4;
        finish_row(row, nullptr, carry, half_tile.cells());
        if (carried >= 0)
            std::copy(row + size_t(carried) * 4, row + size_t(carried) * 4 + 4, carry);
    }
}

}  // namespace

/// A tile that no footprint reaches only carries the light from its left,
/// mostly none (layers are sparse).
void SpreadEngine::spread_carry_tile(const Band& band, const Tile& tile, const Tile& half_tile,
                                     Workspace& ws, RowSink& sink) const
{
    const size_t row_size = size_t(tile.cells()) * 4;
    ws.rows.resize(row_size);
    for (int y = tile.y_begin; y < tile.y_end; ++y) {
        d4 carry = load4(ws.row_carry.data() + size_t(y - tile.y_begin) * 4);
        if (band.half) {
            const auto [j, wy] = half_rows_of(y, half_tile);
            const double* h = ws.half_row_carry.data() + size_t(j) * 4;
            carry += between_rows(h, h + 4, wy);
        }
        double value[4];
        store4(value, carry);
        if (std::all_of(value, value + 4, [](double v) { return v == 0.0; })) {
            sink.dark(y, tile.x_begin, tile.x_end);
            continue;
        }
        for (size_t i = 0; i < row_size; i += 4)
            std::copy(value, value + 4, ws.rows.begin() + ptrdiff_t(i));
        sink.row(y, tile.x_begin, tile.x_end, ws.rows.data() + 4);
    }
}

void SpreadEngine::spread_shape_tile(const Band& band, const Tile& tile, Workspace& ws,
                                     RowSink& sink) const
{
    const int y_begin = tile.y_begin, y_end = tile.y_end;
    const size_t row_size = size_t(tile.cells()) * 4;
    // The half-resolution pixels the tile's pixels interpolate.
    const HalfSpan half_x = half_span(tile.x_begin, tile.x_end);
    const Tile half_tile { band.half_y.begin, band.half_y.end, half_x.begin, half_x.end,
                           tile.first };
    const size_t half_row_size = size_t(half_tile.cells()) * 4;
    // Which of the tile's rows any footprint reaches: full or half
    // resolution.
    bool lit[2] = { false, false };
    visit_item_rows(band, tile, half_tile, ws,
                    [&](int shift, const Reach& reach, const ItemRow& items, int, bool at_half) {
        lit[at_half] = lit[at_half]
                       || !runs_in_reach(items, shift, reach, at_half ? half_tile : tile).empty();
        return !(lit[0] && lit[1]);
    });
    if (!lit[0] && !lit[1]) {
        spread_carry_tile(band, tile, half_tile, ws, sink);
        return;
    }
    // Full-resolution rows no footprint reaches are their carry;
    // half-resolution ones that no footprint reaches and no light from the
    // left crosses add nothing.
    if (lit[0])
        ws.rows.assign(size_t(y_end - y_begin) * row_size, 0.0);
    else
        ws.rows.resize(size_t(y_end - y_begin) * row_size);
    const bool add_half =
        band.half && (lit[1] || !std::all_of(ws.half_row_carry.begin(), ws.half_row_carry.end(),
                                             [](double v) { return v == 0.0; }));
    if (add_half)
        ws.half_rows.assign(size_t(half_tile.y_end - half_tile.y_begin) * half_row_size, 0.0);
    visit_item_rows(band, tile, half_tile, ws,
                    [&](int shift, const Reach& reach,
                        const ItemRow& items, int anchor, bool at_half) {
        if (at_half)
            scatter_items(shift, reach, items, anchor, ws.half_rows.data(), half_tile);
        else
            scatter_items(shift, reach, items, anchor, ws.rows.data(), tile);
        return true;
    });
    if (add_half) {
        const bool last = tile.x_end == band.window.xend;
        finish_half_rows(half_tile,
                         last ? -1 : half_span(tile.x_end, tile.x_end + 1).begin - half_tile.x_begin,
                         ws.half_rows.data(), ws.half_row_carry.data());
    }
    for (int y = y_begin; y < y_end; ++y) {
        double* row = ws.rows.data() + (y - y_begin) * row_size;
        double* carry = ws.row_carry.data() + size_t(y - y_begin) * 4;
        if (lit[0])
            finish_row(row, nullptr, carry, tile.cells());
        if (add_half) {
            const auto [j, wy] = half_rows_of(y, half_tile);
            const double* h0 = ws.half_rows.data() + size_t(j) * half_row_size;
            add_interpolated(row + 4, h0, h0 + half_row_size, wy, tile.x_begin, tile.x_end,
                             half_tile.x_begin - 1, lit[0] ? nullptr : carry);
        }
        sink.row(y, tile.x_begin, tile.x_end, row + 4);
    }
}

}  // namespace defocus
