// Smooth PSFs in constant time: tent and quadratic B-spline.
#include <catch2/catch.hpp>

#include <cmath>

#include <OpenImageIO/imagebufalgo.h>

#include <defocus/spread/spread.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using OIIO::ImageBuf;
using OIIO::ROI;

namespace {

/// Random RGBA over roi (one pixel in `every` lit, values log-uniform in
/// [lo, hi]) and random radii in [rmin, rmax].
void random_layer(const ROI& roi, double lo, double hi, double rmin, double rmax, int every,
                  unsigned seed, ImageBuf& color, ImageBuf& radius)
{
    color = zero_image(roi, 4);
    radius = zero_image(roi, 1);
    Random rng(seed);
    for (int y = roi.ybegin; y < roi.yend; ++y)
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const float r = float(rmin + (rmax - rmin) * rng.uniform());
            radius.setpixel(x, y, &r);
            if (rng.uniform() * every >= 1.0)
                continue;
            float v[4];
            for (float& c : v)
                c = float(lo * std::pow(hi / lo, rng.uniform()));
            color.setpixel(x, y, v);
        }
}

/// Spreads `color` with the order's PSF (2: tent, 3: smooth) and checks it
/// against the direct reference, pixel by pixel, and that it keeps the
/// light of every channel.
void check_against_direct(const ImageBuf& color, const ImageBuf& radius, int order)
{
    ImageBuf fast, direct;
    REQUIRE(spread_smooth(fast, color, radius, order));
    REQUIRE(spread_direct(direct, color, radius,
                          [order](double r) { return smooth_footprint(order, r); }));
    CHECK(worst_relative_error(fast, direct, 1e-5, 1e-7) <= 1.0);
    for (int c = 0; c < 4; ++c)
        CHECK(channel_sum(fast, c) == Approx(channel_sum(color, c)).epsilon(1e-6));
}

}  // namespace

TEST_CASE("tent and smooth spreading equal the direct reference")
{
    const ROI roi(-3, 41, 5, 37);
    for (int order : { 2, 3 })
        // Constant radii (rows filtered as runs), radii of one pair of box
        // widths but varying blends (runs too), and radii all different
        // (pixels spread by their corners, and short runs).
        for (auto [rmin, rmax] : { std::pair { 0.0, 0.0 }, { 4.0, 4.0 }, { 2.3, 2.3 },
                                   { 8.6, 8.9 }, { 0.0, 9.0 } }) {
            INFO("order " << order << " radii " << rmin << ".." << rmax);
            ImageBuf color, radius;
            random_layer(roi, 0.01, 10.0, rmin, rmax, 1, unsigned(order * 100 + rmax * 7), color,
                         radius);
            check_against_direct(color, radius, order);
        }
}

TEST_CASE("a tall layer, accumulated a few rows at a time, equals the direct reference")
{
    // The accumulation holds only the rows about the source rows being
    // read: down a layer 12 times taller than that, every row's light,
    // from runs and from pixels spread by their corners, must come out
    // once and in full.
    const ROI roi(0, 40, -150, 450);
    for (int order : { 2, 3 }) {
        INFO("order " << order);
        ImageBuf color, radius;
        random_layer(roi, 0.01, 10.0, 0.0, 9.0, 3, unsigned(order * 31), color, radius);
        check_against_direct(color, radius, order);
    }
}

TEST_CASE("smooth spreading stays exact at radius 200 on HDR data")
{
    // Sparse highlights from 1e-3 to 1e4 under radius 200 blur, across a
    // frame wide enough for any drift of the repeated integration to show.
    const ROI roi(0, 900, 0, 260);
    ImageBuf color, radius, fast, direct;
    random_layer(roi, 1e-3, 1e4, 195.0, 200.0, 2000, 5, color, radius);
    REQUIRE(spread_smooth(fast, color, radius, 3));
    REQUIRE(spread_direct(direct, color, radius,
                          [](double r) { return smooth_footprint(3, r); }));
    CHECK(worst_relative_error(fast, direct, 1e-4, 1e-6) <= 1.0);
}

TEST_CASE("rows of HDR pixels filtered as runs stay exact at radius 200", "[scale]")
{
    // Long runs of one radius, so that their rows are filtered along x and
    // rounded as profiles: a run of 1e4 sets the fixed point's scale, and
    // runs of 1e-3 and 1 must keep their precision under it, to the
    // tolerance of the direct reference test above.
    const ROI roi(0, 450, 0, 260);
    ImageBuf color = zero_image(roi, 4);
    ImageBuf radius = constant_radius(roi, 200.0f);
    const struct { int y, x0, x1; float value; } runs[] = {
        { 30, 50, 210, 1e4f }, { 120, 190, 400, 1e-3f }, { 200, 0, 450, 1.0f },
        { 201, 25, 350, 1e-3f } };
    for (const auto& run : runs)
        for (int x = run.x0; x < run.x1; ++x) {
            const float v[4] = { run.value, 0.5f * run.value, 2.0f * run.value, 1.0f };
            color.setpixel(x, run.y, v);
        }
    for (int order : { 2, 3 }) {
        INFO("order " << order);
        ImageBuf fast, direct;
        REQUIRE(spread_smooth(fast, color, radius, order));
        REQUIRE(spread_direct(direct, color, radius,
                              [order](double r) { return smooth_footprint(order, r); }));
        CHECK(worst_relative_error(fast, direct, 1e-5, 1e-7) <= 1.0);
    }
}

TEST_CASE("the smooth PSF grows continuously with the radius and peaks in the middle")
{
    ImageBuf last;
    const double largest_step = largest_footprint_step([&](float r) {
        REQUIRE(spread_smooth(last, impulse(), constant_radius(ROI(0, 1, 0, 1), r), 3));
        return last;
    }, 5.0f, 0.01f, 100);
    CHECK(largest_step < 0.02);
    float centre[4], side[4];
    last.getpixel(0, 0, centre);
    last.getpixel(4, 0, side);
    CHECK(centre[0] > side[0]);
    CHECK(side[0] > 0.0f);
}
