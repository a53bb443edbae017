// The cat's eye in bounded time (spread_cateye_bounded): the clipped shape
// taken per cell of the clip's offset, merged in blocks like the disc.
#include <catch2/catch.hpp>

#include <cmath>

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
    const CatEye cateye = corner_clip();
    for (const Aperture& shape : { Aperture(), hexagon() }) {
        INFO(aperture_shape_name(shape.shape));
        auto profile = std::make_shared<ApertureProfile>(shape);
        ImageBuf color, radius;
        random_layer(ROI(-5, 45, 2, 40), 0.0, 7.49, 11, color, radius);
        ImageBuf bounded;
        REQUIRE(spread_cateye_bounded(bounded, color, radius, *profile, cateye));
        const ImageBuf direct = direct_sum(color, radius, bounded, [&](int x, int y, double r) {
            const CatEyeCell cell = cateye_cell(cateye, { x + 0.5, y + 0.5 });
            return aperture_psf(std::make_shared<ClippedProfile>(profile,
                                                                 cateye_cell_offset(cell)))(r);
        });
        CHECK(worst_relative_error(bounded, direct, 1e-5, 1e-7) <= 1.0);
    }
}

TEST_CASE("bounded cat's eye: a cell's offset is within half a step of the pixel's own")
{
    const CatEye cateye = corner_clip();
    for (const double r : { 2.0, 8.0, 30.0, 200.0 }) {
        const int fineness = cateye_fineness(r);
        const double step = cateye_cell_size / (1 << fineness);
        // Fine enough that the clip's edge moves at most 1/8 pixel.
        CHECK(r * 0.5 * step <= 0.125 + 1e-12);
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
    for (auto [rmin, rmax] : { std::pair { 0.0, 7.49 }, { 7.0, 9.0 }, { 14.0, 18.0 },
                               { 30.0, 34.0 }, { 0.0, 70.0 }, { 100.0, 300.0 } }) {
        INFO("radii " << rmin << ".." << rmax);
        ImageBuf color, radius;
        random_layer(ROI(3, 83, -7, 60), rmin, rmax, unsigned(rmax), color, radius);
        ImageBuf clipped, fixed;
        REQUIRE(spread_cateye_bounded(clipped, color, radius, *disc, cateye, merge_all));
        for (int c = 0; c < 4; ++c)
            CHECK(channel_sum(clipped, c) == Approx(channel_sum(color, c)).epsilon(1e-6));
        CHECK(cateye_cell(cateye, { 3.5, -6.5 }) == cateye_cell(cateye, { 82.5, 59.5 }));
        const ClippedProfile shape(disc, cateye_cell_offset(cateye_cell(cateye, { 40.5, 20.5 })));
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
    // Its clip's edge lies within 1/8 pixel of its own: along the outline
    // (under 250 px) that moves under 250 x 1/8 x 0.42 (its intensity), 1.3%
    // of its light. Merged, it would move by blocks of 4 or 8 pixels.
    OIIO::ImageBuf diff;
    REQUIRE(OIIO::ImageBufAlgo::absdiff(diff, bounded, exact));
    CHECK(channel_sum(diff, 0) < 0.015 * 1000.0);
}
