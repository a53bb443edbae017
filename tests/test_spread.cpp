// The rectangle-spreading filter against the direct reference.
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

/// A random RGBA layer over `roi` with values log-uniform in [lo, hi] and
/// one in `holes` pixels left empty, and random radii in [rmin, rmax].
struct RandomLayer {
    ImageBuf color, radius;
    RandomLayer(const ROI& roi, double lo, double hi, double rmin, double rmax,
                unsigned seed, int holes = 5)
        : color(zero_image(roi, 4)), radius(zero_image(roi, 1))
    {
        Random rng(seed);
        for (int y = roi.ybegin; y < roi.yend; ++y)
            for (int x = roi.xbegin; x < roi.xend; ++x) {
                float rgba[4] = { 0, 0, 0, 0 };
                if (rng.uniform() * holes >= 1.0)
                    for (float& v : rgba)
                        v = float(lo * std::pow(hi / lo, rng.uniform()));
                color.setpixel(x, y, rgba);
                const float r = float(rmin + (rmax - rmin) * rng.uniform());
                radius.setpixel(x, y, &r);
            }
    }
};


}  // namespace

TEST_CASE("box footprint covers the CoC disc's area with fractional edges")
{
    for (double r : { 0.0, 0.3, 1.0, 2.5, 3.0, 3.25, 7.9, 40.0 }) {
        const Footprint fp = box_footprint(r);
        double sum = 0.0;
        for (double w : fp.weights)
            sum += w;
        CHECK(sum == Approx(1.0).epsilon(1e-12));
        // The side is the square root of the disc's area, or one pixel.
        const double side = std::max(1.0, r * std::sqrt(M_PI));
        CHECK(fp.at(-fp.x0, -fp.y0) == Approx(1.0 / (side * side)));
    }
    const Footprint in_focus = box_footprint(0.0);
    CHECK(in_focus.x0 == 0);
    CHECK(in_focus.at(0, 0) == 1.0);
}

TEST_CASE("spreading equals the direct reference at integer and fractional radii")
{
    const ROI roi(-7, 57, 3, 51);
    for (auto [rmin, rmax] : { std::pair { 0.0, 0.0 }, { 1.0, 1.0 }, { 4.0, 4.0 },
                               { 2.37, 2.37 }, { 0.0, 9.5 }, { 5.5, 14.25 } }) {
        INFO("radii in [" << rmin << ", " << rmax << "]");
        RandomLayer layer(roi, 0.01, 10.0, rmin, rmax, unsigned(rmax * 100 + rmin));
        ImageBuf fast, direct;
        REQUIRE(spread_box(fast, layer.color, layer.radius));
        REQUIRE(spread_direct(direct, layer.color, layer.radius, box_footprint));
        CHECK(fast.roi() == direct.roi());
        CHECK(worst_relative_error(fast, direct, 1e-5, 1e-7) <= 1.0);
    }
}

TEST_CASE("squeezed boxes equal the direct reference of their rectangles")
{
    const ROI roi(-7, 57, 3, 51);
    for (const double aspect : { 0.5, 0.3, 2.0, 3.7 }) {
        INFO("aspect " << aspect);
        RandomLayer layer(roi, 0.01, 10.0, 0.0, 11.5, unsigned(aspect * 10));
        ImageBuf fast, direct;
        REQUIRE(spread_box(fast, layer.color, layer.radius, aspect));
        REQUIRE(spread_direct(direct, layer.color, layer.radius,
                              [aspect](double r) { return rectangle_footprint(r, aspect); }));
        CHECK(fast.roi() == direct.roi());
        CHECK(worst_relative_error(fast, direct, 1e-5, 1e-7) <= 1.0);
    }
    // Of the disc's area, and as wide as tall only at aspect 1.
    const Footprint wide = rectangle_footprint(20.0, 4.0);
    CHECK(wide.width == Approx(4 * wide.height).epsilon(0.1));
    const BoxHalfWidths h = box_half_widths(20.0, 4.0);
    CHECK(4 * h.x * h.y == Approx(3.14159265358979 * 400));
}

TEST_CASE("spreading conserves energy and grows the data window")
{
    const ROI roi(0, 40, 0, 30);
    RandomLayer layer(roi, 0.1, 100.0, 0.0, 12.0, 7);
    ImageBuf out;
    REQUIRE(spread_box(out, layer.color, layer.radius));
    for (int c = 0; c < 4; ++c)
        CHECK(channel_sum(out, c) == Approx(channel_sum(layer.color, c)).epsilon(1e-6));
    // Radius 12 -> half-width 10.63: the result reaches 10 pixels further.
    CHECK(out.roi().xbegin <= -10);
    CHECK(out.roi().xend >= 50);
}

TEST_CASE("an in-focus layer comes out unchanged")
{
    const ROI roi(0, 32, 0, 24);
    RandomLayer layer(roi, 0.001, 1000.0, 0.0, 0.0, 3);
    ImageBuf out;
    REQUIRE(spread_box(out, layer.color, constant_radius(roi, 0.0f)));
    CHECK(worst_relative_error(out, layer.color, 1e-6, 1e-9) <= 1.0);
}

TEST_CASE("the footprint changes continuously with the radius")
{
    // An impulse spread at radii 3.0 .. 4.0 in steps of 0.01: a step of the
    // radius must never move more than its share of the energy. With
    // integer-snapped boxes a change of size moves most of it at once.
    const ImageBuf one = impulse();
    const double largest_step = largest_footprint_step([&](float r) {
        ImageBuf out;
        REQUIRE(spread_box(out, one, constant_radius(one.roi(), r)));
        return out;
    }, 3.0f, 0.01f, 100);
    // Smoothly, a step moves about 4·ds/s of the energy (side s = r·√π,
    // ds = 0.01·√π): 0.013 here. Snapping the side to whole pixels would
    // move ~0.6 at once.
    CHECK(largest_step < 0.02);
}

TEST_CASE("a tilted plane shows no banding")
{
    // A constant plane whose blur grows from left to right. Spreading with
    // varying sizes does not keep a constant exactly, but with fractional
    // coverage the deviation stays below 0.5%. Boxes snapped to whole
    // pixels give a ~3% step each time the size changes (3/5 + 3/7 where a
    // 5-pixel box meets a 7-pixel box): visible bands.
    const ROI roi(0, 200, 0, 40);
    ImageBuf color = zero_image(roi, 4), radius = zero_image(roi, 1);
    OIIO::ImageBufAlgo::fill(color, { 0.5f, 0.5f, 0.5f, 1.0f });
    for (int y = 0; y < 40; ++y)
        for (int x = 0; x < 200; ++x) {
            const float r = 2.0f + 0.02f * x;
            radius.setpixel(x, y, &r);
        }
    ImageBuf out;
    REQUIRE(spread_box(out, color, radius));
    double worst = 0.0;
    for (int x = 30; x < 170; ++x) {
        float p[4];
        out.getpixel(x, 20, p);
        worst = std::max(worst, std::abs(p[0] / 0.5 - 1.0));
    }
    CHECK(worst < 0.005);
}

TEST_CASE("prefix sums stay accurate on a 4096x2160 HDR layer", "[scale]")
{
    // Values 1e-3..1e4: the result must equal the direct reference within
    // 1e-4 of the local value plus 1e-6 everywhere.
    const ROI roi(0, 4096, 0, 2160);
    RandomLayer layer(roi, 1e-3, 1e4, 0.0, 5.0, 11, 3);
    ImageBuf fast, direct;
    REQUIRE(spread_box(fast, layer.color, layer.radius));
    REQUIRE(spread_direct(direct, layer.color, layer.radius, box_footprint));
    CHECK(worst_relative_error(fast, direct, 1e-4, 1e-6) <= 1.0);
}

TEST_CASE("bad radius images are reported, not crashed on")
{
    const ROI roi(0, 8, 0, 8);
    ImageBuf color = zero_image(roi, 4);
    OIIO::ImageBufAlgo::fill(color, { 1.0f, 1.0f, 1.0f, 1.0f });
    ImageBuf out;
    CHECK_FALSE(spread_box(out, color, zero_image(roi, 3)));
    CHECK(out.has_error());
    ImageBuf small = zero_image(ROI(0, 4, 0, 4), 1);
    ImageBuf out2;
    CHECK_FALSE(spread_box(out2, color, small));
    ImageBuf huge = constant_radius(roi, INFINITY);
    ImageBuf out3;
    CHECK_FALSE(spread_box(out3, color, huge));
}
