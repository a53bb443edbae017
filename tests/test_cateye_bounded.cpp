// The cat's eye in bounded time (spread_cateye_bounded): the clipped shape
// taken per cell of the clip's offset, merged in blocks like the disc.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <tuple>

#include <OpenImageIO/imagebufalgo.h>

#include <defocus/color/color.h>
#include <defocus/spread/cateye.h>
#include <defocus/spread/spread.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using OIIO::ImageBuf;
using OIIO::ROI;

namespace {

/// A clip over a small layer as over a frame's corner: every pixel cut.
CatEye corner_clip()
{
    CatEye cateye;
    cateye.amount = 1.0;
    cateye.centre = Imath::V2d(60.0, 50.0);
    cateye.corner_distance = 80.0;
    return cateye;
}

}  // namespace

TEST_CASE("bounded cat's eye: below radius 7.5 each pixel is its cell's clipped shape")
{
    // In front of the focus too, where the clip is mirrored.
    CatEye cateye = corner_clip();
    for (const double side : { 1.0, -1.0 })
    for (const Aperture& shape : { Aperture(), hexagon() }) {
        cateye.side = side;
        INFO(aperture_shape_name(shape.shape) << ", side " << side);
        auto profile = std::make_shared<ApertureProfile>(shape);
        ImageBuf color, radius;
        random_layer(ROI(-5, 45, 2, 40), 0.0, 7.49, 11, color, radius);
        ImageBuf bounded;
        REQUIRE(spread_cateye_bounded(bounded, color, radius, *profile, cateye));
        const ImageBuf direct = direct_sum(color, radius, bounded, [&](int x, int y, double r) {
            const CatEyeCell cell = cateye_cell(cateye, { x + 0.5, y + 0.5 });
            return aperture_psf(std::make_shared<ClippedProfile>(
                profile, cateye_cell_offset(cell), cateye.clip_aspect))(r);
        });
        CHECK(worst_relative_error(bounded, direct, 1e-5, 1e-7) <= 1.0);
    }
}

TEST_CASE("bounded cat's eye: a cell's offset is within half a step of the pixel's own")
{
    const CatEye cateye = corner_clip();
    // Single pixels of radius r, and blocks of 2, 4 and 8 at the largest
    // radius they take.
    for (const auto [block, r] : { std::pair { 1, 2.0 }, { 1, 8.0 }, { 1, 30.0 }, { 1, 200.0 },
                                   { 2, 16.0 }, { 4, 64.0 }, { 8, 128.0 } }) {
        INFO("block " << block << " radius " << r);
        const int fineness = cateye_fineness(block, r);
        const double step = std::ldexp(cateye_cell_size, -fineness);
        // The clip's edge moves at most r / 64 and half a pixel, or a
        // quarter of a block.
        CHECK(r * 0.5 * step <= (block == 1 ? std::min(r / 64.0, 0.5) : 0.25 * block) + 1e-12);
        CHECK(cateye_cell_offset(cateye_cell(cateye, cateye.centre, fineness))
              == Imath::V2d(0.0, 0.0));
        for (const Imath::V2d at : { Imath::V2d(0.5, 0.5), Imath::V2d(13.5, 71.5),
                                     Imath::V2d(59.5, 49.5) }) {
            const Imath::V2d own = cateye.offset(at, 1.0);
            const Imath::V2d cell = cateye_cell_offset(cateye_cell(cateye, at, fineness));
            CHECK(std::abs(cell.x - own.x) <= 0.5 * step + 1e-12);
            CHECK(std::abs(cell.y - own.y) <= 0.5 * step + 1e-12);
        }
    }
}

TEST_CASE("bounded cat's eye: where the offset is one cell's, it is that clipped shape "
          "spread in bounded time, and keeps every channel's light")
{
    // A centre so far away that the offset per unit of radius, about
    // (0.62, -0.34), changes by 1e-6 across the layer: every pixel and
    // block lies in one cell of every grid.
    CatEye cateye;
    cateye.amount = 1.0;
    cateye.centre = Imath::V2d(5.5e5, -3.0e5);
    cateye.corner_distance = 1.0e6;
    // Highlights would take finer grids (see the next test).
    const HighlightTest merge_all {};
    auto disc = std::make_shared<ApertureProfile>(Aperture());
    // Radii within one grid: single pixels and blocks of every size (see
    // cateye_fineness).
    for (auto [rmin, rmax, block] : { std::tuple { 0.0, 7.49, 1 }, { 7.0, 9.0, 2 },
                                      { 14.0, 18.0, 4 }, { 0.0, 70.0, 4 },
                                      { 100.0, 300.0, 8 } }) {
        INFO("radii " << rmin << ".." << rmax);
        ImageBuf color, radius;
        random_layer(ROI(3, 83, -7, 60), rmin, rmax, unsigned(rmax), color, radius);
        ImageBuf clipped, fixed;
        REQUIRE(spread_cateye_bounded(clipped, color, radius, *disc, cateye, merge_all));
        for (int c = 0; c < 4; ++c)
            CHECK(channel_sum(clipped, c) == Approx(channel_sum(color, c)).epsilon(1e-6));
        const int fineness = cateye_fineness(block, rmax);
        const CatEyeCell cell = cateye_cell(cateye, { 40.5, 20.5 }, fineness);
        CHECK(cateye_cell(cateye, { 3.5, -6.5 }, fineness) == cell);
        CHECK(cateye_cell(cateye, { 82.5, 59.5 }, fineness) == cell);
        const ClippedProfile shape(disc, cateye_cell_offset(cell), cateye.clip_aspect);
        REQUIRE(spread_aperture(fixed, color, radius, shape, merge_all));
        CHECK(worst_relative_error(clipped, fixed, 1e-6, 1e-9) <= 1.0);
    }
}

TEST_CASE("bounded cat's eye: a highlight keeps its exact clipped bokeh among merged pixels")
{
    // As for the unclipped disc: a bright point on a dim field at radius 40
    // is spread on its own, on a grid fine enough for its outline.
    ImageBuf color, radius;
    highlight_on_dim_field(ROI(0, 200, 0, 200), Imath::V2i(31, 27), color, radius);
    CatEye cateye = corner_clip();
    cateye.centre = Imath::V2d(200.0, 200.0);
    cateye.corner_distance = 283.0;
    const ApertureProfile profile{Aperture()};
    ImageBuf bounded, exact;
    REQUIRE(spread_cateye_bounded(bounded, color, radius, profile, cateye,
                                  { exact_highlight_threshold, luma_weights(nullptr) }));
    REQUIRE(spread_cateye(exact, color, radius, profile, cateye));
    // Its clip's edge lies within half a step of its grid times the radius
    // of its own (40 / 128 pixel): along the outline (under 250 px) that
    // moves under 250 x 40 / 128 x 0.42 (its intensity), 3.3% of its light.
    // Merged, it would move by blocks of 4 or 8 pixels.
    CHECK(40.0 * 0.5 * std::ldexp(cateye_cell_size, -cateye_fineness(1, 40.0)) == 40.0 / 128.0);
    OIIO::ImageBuf diff;
    REQUIRE(OIIO::ImageBufAlgo::absdiff(diff, bounded, exact));
    CHECK(channel_sum(diff, 0) < 0.033 * 1000.0);
}
