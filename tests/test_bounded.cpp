// Bounded-time spreading of shapes (spread_aperture), the default for the
// disc, polygon and mask: exact below radius 7.5, merged in blocks above.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

#include <OpenImageIO/imagebufalgo.h>

#include <defocus/color/color.h>
#include <defocus/spread/spread.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using OIIO::ImageBuf;
using OIIO::ROI;

namespace {

/// No pixel counts as a highlight: every large footprint is merged.
const HighlightTest merge_all {};

}  // namespace

TEST_CASE("below radius 7.5 the bounded disc is the exact disc")
{
    auto profile = std::make_shared<ApertureProfile>(Aperture());
    ImageBuf color, radius;
    random_layer(ROI(-5, 45, 2, 40), 0.0, 7.49, 7, color, radius);
    ImageBuf bounded, direct;
    REQUIRE(spread_aperture(bounded, color, radius, *profile, merge_all));
    REQUIRE(spread_direct(direct, color, radius, aperture_psf(profile)));
    CHECK(worst_relative_error(bounded, direct, 1e-5, 1e-7) <= 1.0);
}

TEST_CASE("bounded spreading keeps every channel's energy at every radius and shape")
{
    for (const Aperture& shape : { Aperture(), hexagon() }) {
        const ApertureProfile profile(shape);
        for (auto [rmin, rmax] : { std::pair { 7.0, 9.0 }, { 14.0, 18.0 }, { 0.0, 70.0 },
                                   { 100.0, 300.0 } }) {
            INFO(aperture_shape_name(shape.shape) << " radii " << rmin << ".." << rmax);
            ImageBuf color, radius;
            random_layer(ROI(3, 83, -7, 60), rmin, rmax, unsigned(rmax), color, radius);
            ImageBuf out;
            REQUIRE(spread_aperture(out, color, radius, profile, merge_all));
            for (int c = 0; c < 4; ++c)
                CHECK(channel_sum(out, c) == Approx(channel_sum(color, c)).epsilon(1e-6));
        }
    }
}

TEST_CASE("merged blocks leave a uniform field uniform")
{
    // Blocks of 4 pixels at radius 40. A block spreads the exact footprint
    // of a uniform block (each of its pixels' shapes on the pixel's own
    // centre), so a uniform field comes out as uniform as exact spreading
    // makes it: no ripple where the disc's edges fall between blocks.
    const ROI roi(0, 300, 0, 300);
    ImageBuf color = zero_image(roi, 4);
    OIIO::ImageBufAlgo::fill(color, { 1.0f, 0.5f, 0.25f, 1.0f });
    ImageBuf out;
    REQUIRE(spread_aperture(out, color, constant_radius(roi, 40.0f), ApertureProfile(Aperture()),
                            merge_all));
    const ROI inside(60, 240, 60, 240, 0, 1, 0, 4);
    const auto stats = OIIO::ImageBufAlgo::computePixelStats(out, inside);
    CHECK(stats.min[3] == Approx(1.0).epsilon(1e-5));
    CHECK(stats.max[3] == Approx(1.0).epsilon(1e-5));
    CHECK(stats.min[0] == Approx(1.0).epsilon(1e-5));
    CHECK(stats.max[2] == Approx(0.25).epsilon(1e-5));
}

TEST_CASE("a merged footprint changes continuously where the block size changes")
{
    // Blocks of 2 take over from single pixels between radius 7.5 and 8,
    // blocks of 4 from blocks of 2 between 15 and 16, blocks of 8 (whose
    // footprint is no longer exact) from blocks of 4 between 60 and 64: an
    // impulse's footprint must not jump there.
    const ApertureProfile profile{Aperture()};
    auto spread_at = [&](float r) {
        ImageBuf out;
        REQUIRE(spread_aperture(out, impulse(), constant_radius(ROI(0, 1, 0, 1), r), profile,
                                merge_all));
        return out;
    };
    // Smoothly, a 0.01 px step moves about 2·0.01/r of the energy; moving
    // the centre by 1/2 pixel over 1 pixel of radius adds about as much.
    CHECK(largest_footprint_step(spread_at, 7.3f, 0.01f, 80) < 0.01);
    CHECK(largest_footprint_step(spread_at, 14.8f, 0.01f, 140) < 0.01);
    CHECK(largest_footprint_step(spread_at, 59.6f, 0.01f, 460) < 0.01);
}

TEST_CASE("a highlight keeps its exact bokeh among merged pixels")
{
    // A bright point on a dim field at radius 40: its outline is what the
    // eye sees, so it is spread in place, never merged.
    ImageBuf color, radius;
    highlight_on_dim_field(ROI(0, 200, 0, 200), Imath::V2i(101, 97), color, radius);
    const ApertureProfile profile{Aperture()};
    ImageBuf bounded, exact;
    REQUIRE(spread_aperture(bounded, color, radius, profile,
                            { exact_highlight_threshold, luma_weights(nullptr) }));
    REQUIRE(spread_scanline(exact, color, radius, profile));
    // The highlight lights each pixel of its disc with 1000 / (pi 40^2),
    // about 0.2, so a merged highlight would differ by that much at its
    // edge; merging the dim field (about 0.005) moves under 1% of that.
    OIIO::ImageBufAlgo::CompareResults diff
        = OIIO::ImageBufAlgo::compare(bounded, exact, 0.0f, 0.0f);
    CHECK(diff.maxerror < 1e-4);
}

TEST_CASE("an even card on a transparent field stays opaque inside its blur")
{
    // An opaque card as a layer holds it, transparent around it, at CoC
    // radius 12.9 (blocks of 2). Its corners pass the highlight test
    // (against a window that is mostly transparent) and go the exact way;
    // blocks those pixels left holes in spread their light as if even over
    // the block, and the card came out 0.45% see-through 14 pixels inside
    // its edges. As a flat render, and spread exactly, it is opaque.
    const ROI roi(0, 200, 0, 180);
    ImageBuf color = zero_image(roi, 4);
    OIIO::ImageBufAlgo::fill(color, { 0.4f, 0.3f, 0.2f, 1.0f }, ROI(41, 161, 31, 151));
    const ApertureProfile profile{Aperture()};
    ImageBuf out;
    REQUIRE(spread_aperture(out, color, constant_radius(roi, 12.9f), profile,
                            { exact_highlight_threshold, luma_weights(nullptr) }));
    const auto inside
        = OIIO::ImageBufAlgo::computePixelStats(out, ROI(55, 147, 45, 137, 0, 1, 0, 4));
    // Exact and merged footprints are tabulated at radii a quarter and a
    // half pixel apart: where they meet they add up to 1 within 1e-3.
    CHECK(inside.min[3] >= 0.999);
    CHECK(inside.max[3] <= 1.001);
}
