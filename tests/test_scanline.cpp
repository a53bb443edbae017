// Scanline spreading of disc and polygon apertures.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>

#include <OpenImageIO/imagebufalgo.h>

#include <defocus/io/aperture_files.h>
#include <defocus/color/color.h>
#include <defocus/spread/cateye.h>
#include <defocus/spread/spread.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using OIIO::ImageBuf;
using OIIO::ROI;

namespace {

Aperture polygon(int blades, double rotation = 0.0, double roundness = 0.0, double aspect = 1.0)
{
    Aperture a;
    a.shape = ApertureShape::Polygon;
    a.blades = blades;
    a.rotation_deg = rotation;
    a.roundness = roundness;
    a.aspect = aspect;
    return a;
}

/// Number of pixels an impulse lights, weighted by coverage: the area.
double lit_area(const ImageBuf& image)
{
    double peak = 0.0, sum = 0.0;
    for (OIIO::ImageBuf::ConstIterator<float> it(image); !it.done(); ++it) {
        peak = std::max(peak, double(it[0]));
        sum += it[0];
    }
    return sum / peak;  // interior pixels carry the peak, 1/area each
}

}  // namespace

TEST_CASE("scanline spreading equals the direct reference for discs and polygons")
{
    const ROI roi(-5, 45, 2, 40);
    for (const Aperture& shape : { Aperture(), polygon(6), polygon(5, 17.0, 0.3, 0.6) }) {
        auto profile = std::make_shared<ApertureProfile>(shape);
        for (auto [rmin, rmax] : { std::pair { 0.0, 0.0 }, { 3.0, 3.0 }, { 4.6, 4.6 },
                                   { 0.0, 11.5 } }) {
            INFO(aperture_shape_name(shape.shape) << " radii " << rmin << ".." << rmax);
            ImageBuf color, radius;
            random_layer(roi, rmin, rmax, unsigned(rmax * 10 + shape.blades), color, radius);
            ImageBuf fast, direct;
            REQUIRE(spread_scanline(fast, color, radius, *profile));
            REQUIRE(spread_direct(direct, color, radius, aperture_psf(profile)));
            CHECK(worst_relative_error(fast, direct, 1e-5, 1e-7) <= 1.0);
            for (int c = 0; c < 4; ++c)
                CHECK(channel_sum(fast, c) == Approx(channel_sum(color, c)).epsilon(1e-6));
        }
    }
}

TEST_CASE("an impulse lights the analytic shape: disc pi r^2, inscribed hexagon 3 sqrt(3)/2 r^2")
{
    const double r = 20.0;
    const ImageBuf one = impulse();
    ImageBuf disc, hexagon;
    const ApertureProfile disc_profile{Aperture()};
    REQUIRE(spread_scanline(disc, one, constant_radius(one.roi(), float(r)), disc_profile));
    CHECK(lit_area(disc) == Approx(M_PI * r * r).epsilon(0.01));
    CHECK(channel_sum(disc, 0) == Approx(1.0).epsilon(1e-6));
    // As render cameras draw it: the hexagon inscribed in the CoC circle.
    const ApertureProfile hex_profile(polygon(6));
    std::vector<RowSpan> spans;
    // The outline is tabulated at 4096 heights: exact to about 1e-4.
    CHECK(hex_profile.rows(r, spans) == Approx(3.0 * std::sqrt(3.0) / 2.0 * r * r).epsilon(2e-4));
    REQUIRE(spread_scanline(hexagon, one, constant_radius(one.roi(), float(r)), hex_profile));
    CHECK(lit_area(hexagon) == Approx(3.0 * std::sqrt(3.0) / 2.0 * r * r).epsilon(0.01));
    CHECK(channel_sum(hexagon, 0) == Approx(1.0).epsilon(1e-6));
    // Its vertices lie on the circle: with one pointing right, it reaches
    // r along x and r·√3/2 (its edge) along y.
    float p[4];
    hexagon.getpixel(int(r) - 1, 0, p);
    CHECK(p[0] > 0.0f);
    hexagon.getpixel(int(r) + 1, 0, p);
    CHECK(p[0] == 0.0f);
    hexagon.getpixel(0, int(r * std::sqrt(3.0) / 2.0) + 2, p);
    CHECK(p[0] == 0.0f);
    hexagon.getpixel(0, int(r * std::sqrt(3.0) / 2.0) - 2, p);
    CHECK(p[0] > 0.0f);
}

TEST_CASE("a polygon's rotation turns it clockwise in the image, as renderers do")
{
    // A triangle with a vertex pointing right, turned by 90 degrees
    // clockwise (image y points down): its vertex points down, and its
    // top is an edge r/2 above the centre.
    const double r = 20.0;
    const ImageBuf one = impulse();
    ImageBuf triangle;
    REQUIRE(spread_scanline(triangle, one, constant_radius(one.roi(), float(r)),
                            ApertureProfile(polygon(3, 90.0))));
    float p[4];
    triangle.getpixel(0, int(r) - 2, p);
    CHECK(p[0] > 0.0f);
    triangle.getpixel(0, -int(r / 2) - 2, p);
    CHECK(p[0] == 0.0f);
    triangle.getpixel(0, -int(r / 2) + 2, p);
    CHECK(p[0] > 0.0f);
}

TEST_CASE("roundness 1 makes the polygon the disc")
{
    std::vector<RowSpan> disc, round;
    const double r = 13.3;
    const double disc_area = ApertureProfile(Aperture()).rows(r, disc);
    CHECK(disc_area == Approx(M_PI * r * r).epsilon(1e-5));
    CHECK(ApertureProfile(polygon(5, 30.0, 1.0)).rows(r, round) == Approx(disc_area).epsilon(1e-9));
    REQUIRE(round.size() == disc.size());
    for (size_t i = 0; i < disc.size(); ++i) {
        CHECK(round[i].left == Approx(disc[i].left).margin(1e-6));
        CHECK(round[i].right == Approx(disc[i].right).margin(1e-6));
    }
}

TEST_CASE("anamorphic squeeze narrows the bokeh horizontally")
{
    const ImageBuf one = impulse();
    ImageBuf squeezed;
    Aperture a;
    a.aspect = 0.5;
    REQUIRE(spread_scanline(squeezed, one, constant_radius(one.roi(), 16.0f), ApertureProfile(a)));
    float p[4];
    squeezed.getpixel(14, 0, p);  // beyond 16·√0.5 = 11.3 horizontally
    CHECK(p[0] == 0.0f);
    squeezed.getpixel(0, 20, p);  // within 16/√0.5 = 22.6 vertically
    CHECK(p[0] > 0.0f);
}

TEST_CASE("a disc footprint changes continuously with the radius")
{
    const ApertureProfile profile{Aperture()};
    const double largest_step = largest_footprint_step([&](float r) {
        ImageBuf out;
        REQUIRE(spread_scanline(out, impulse(), constant_radius(ROI(0, 1, 0, 1), r), profile));
        return out;
    }, 3.0f, 0.01f, 100);
    // Smoothly, a 0.01 px step moves about 2·0.01/r of the energy.
    CHECK(largest_step < 0.02);
}

TEST_CASE("an in-focus pixel stays itself under a disc, exact or bounded")
{
    const ImageBuf one = impulse();
    const ImageBuf zero = constant_radius(one.roi(), 0.0f);
    const ApertureProfile disc{Aperture()};
    ImageBuf exact, bounded;
    REQUIRE(spread_scanline(exact, one, zero, disc));
    REQUIRE(spread_aperture(bounded, one, zero, disc));
    for (const ImageBuf* out : { &exact, &bounded }) {
        float p[4];
        out->getpixel(0, 0, p);
        CHECK(p[0] == Approx(1.0f).epsilon(1e-6));
    }
}

namespace {

/// A size x size mask image: a ring (radii 0.55 and 1 of the half-size),
/// or a plain disc, written for a test.
std::string write_mask(const std::string& name, double inner, int size = 64)
{
    const std::string path = scratch_dir("mask_" + name) + "/" + name + ".exr";
    ImageBuf mask = zero_image(ROI(0, size, 0, size), 1);
    const double half = 0.5 * size;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const double r = std::hypot(x + 0.5 - half, y + 0.5 - half) / half;
            const float v = r <= 1.0 && r >= inner ? 1.0f : 0.0f;
            mask.setpixel(x, y, &v);
        }
    // Written beside and renamed over, as the tools write: OpenImageIO
    // does not see the file change.
    const std::string written = path + ".new.exr";
    REQUIRE(mask.write(written));
    std::filesystem::rename(written, path);
    return path;
}

std::shared_ptr<MaskProfile> load_mask(const std::string& path, double max_radius)
{
    auto mask = std::make_shared<MaskProfile>();
    std::string error;
    INFO(error);
    REQUIRE(read_aperture_mask(path, 1.0, luma_weights(nullptr), *mask, error));
    return mask;
}

}  // namespace

TEST_CASE("a mask aperture, holes and all, equals the direct reference")
{
    const auto ring = load_mask(write_mask("ring", 0.55), 12.0);
    const ROI roi(0, 40, 0, 30);
    ImageBuf color = zero_image(roi, 4), radius = zero_image(roi, 1);
    Random rng(3);
    for (int y = 0; y < 30; ++y)
        for (int x = 0; x < 40; ++x) {
            float v[4] = { float(rng.uniform()), float(rng.uniform()), 0.5f, 1.0f };
            color.setpixel(x, y, v);
            const float r = float(11.5 * rng.uniform());
            radius.setpixel(x, y, &r);
        }
    ImageBuf fast, direct;
    REQUIRE(spread_scanline(fast, color, radius, *ring));
    REQUIRE(spread_direct(direct, color, radius, aperture_psf(ring)));
    CHECK(worst_relative_error(fast, direct, 1e-5, 1e-7) <= 1.0);
    CHECK(channel_sum(fast, 3) == Approx(channel_sum(color, 3)).epsilon(1e-6));

    // On an impulse the ring keeps its hole: at radius 20 it spans 13 to
    // 24 pixels from the centre (its area is the disc's).
    const auto wide_ring = load_mask(write_mask("ring", 0.55), 20.0);
    ImageBuf out;
    REQUIRE(spread_scanline(out, impulse(), constant_radius(ROI(0, 1, 0, 1), 20.0f), *wide_ring));
    float p[4];
    out.getpixel(0, 0, p);
    CHECK(p[0] == Approx(0.0f).margin(1e-9));  // prefix-sum rounding only
    out.getpixel(20, 0, p);
    CHECK(p[0] > 1e-4f);
}

TEST_CASE("a disc drawn as a mask lights the disc's area, continuously in size")
{
    const auto disc = load_mask(write_mask("disc", 0.0), 21.0);
    ImageBuf out;
    REQUIRE(spread_scanline(out, impulse(), constant_radius(ROI(0, 1, 0, 1), 20.0f), *disc));
    CHECK(lit_area(out) == Approx(M_PI * 400.0).epsilon(0.02));
    CHECK(channel_sum(out, 0) == Approx(1.0).epsilon(1e-6));
    const double largest_step = largest_footprint_step([&](float r) {
        ImageBuf step;
        REQUIRE(spread_scanline(step, impulse(), constant_radius(ROI(0, 1, 0, 1), r), *disc));
        return step;
    }, 5.0f, 0.01f, 50);
    CHECK(largest_step < 0.03);
}

TEST_CASE("a mask rewritten larger under the same name is read as it is now")
{
    // OpenImageIO's shared cache remembers a file's first size; reading
    // through it overran the buffer (a crash) or gave the old mask.
    const auto ring = load_mask(write_mask("rewritten", 0.55, 16), 21.0);
    const auto disc = load_mask(write_mask("rewritten", 0.0, 128), 21.0);
    ImageBuf out;
    REQUIRE(spread_scanline(out, impulse(), constant_radius(ROI(0, 1, 0, 1), 20.0f), *disc));
    CHECK(lit_area(out) == Approx(M_PI * 400.0).epsilon(0.02));
    float centre[4];
    out.getpixel(0, 0, centre);
    CHECK(centre[0] > 1e-4f);  // a disc: no hole
}

TEST_CASE("cat's eye: clipped scanline spreading equals its direct reference, keeps light, "
          "and cuts the predicted lens shape")
{
    const ROI roi(-5, 45, 2, 40);
    CatEye cateye;
    cateye.amount = 1.0;
    cateye.centre = Imath::V2d(60.0, 50.0);  // off the layer: every pixel is clipped
    cateye.corner_distance = 80.0;
    for (const Aperture& shape : { Aperture(), polygon(6, 10.0), polygon(5, 17.0, 0.3, 0.6) }) {
        const ApertureProfile profile(shape);
        ImageBuf color, radius;
        random_layer(roi, 0.0, 11.5, 7u + unsigned(shape.blades), color, radius);
        ImageBuf fast;
        REQUIRE(spread_cateye(fast, color, radius, profile, cateye));
        // The direct reference: every pixel adds its own footprint table.
        const ImageBuf direct = direct_sum(color, radius, fast, [&](int x, int y, double r) {
            return cateye_footprint(profile, cateye, { x + 0.5, y + 0.5 }, r);
        });
        INFO(aperture_shape_name(shape.shape) << " " << shape.blades);
        CHECK(worst_relative_error(fast, direct, 1e-4, 1e-6) <= 1.0);
        for (int c = 0; c < 4; ++c)
            CHECK(channel_sum(fast, c) == Approx(channel_sum(color, c)).epsilon(1e-6));
    }

    // At the farthest corner with amount 1 the clip disc's edge passes the
    // bokeh's centre: a disc cut by an equal disc a radius away, the lens
    // of area (2π/3 - √3/2) r². Nearer the centre less is cut.
    const double r = 30.0;
    const ApertureProfile disc{Aperture()};
    auto lit = [](const Footprint& fp) {
        double peak = 0.0, sum = 0.0;
        for (double w : fp.weights) {
            peak = std::max(peak, w);
            sum += w;
        }
        CHECK(sum == Approx(1.0).epsilon(1e-9));
        return sum / peak;
    };
    const Imath::V2d corner = cateye.centre - Imath::V2d(80.0, 0.0);
    CHECK(lit(cateye_footprint(disc, cateye, corner, r))
          == Approx((2.0 * M_PI / 3.0 - std::sqrt(3.0) / 2.0) * r * r).epsilon(0.02));
    CHECK(lit(cateye_footprint(disc, cateye, cateye.centre, r))
          == Approx(M_PI * r * r).epsilon(0.01));
    // The cut is on the side away from the centre: the corner's bokeh
    // reaches r towards the centre (+x) and only to its own centre away.
    const Footprint cut = cateye_footprint(disc, cateye, corner, r);
    CHECK(cut.x0 >= -1);
    CHECK(cut.x0 + cut.width >= int(r) - 1);

    // Soft PSFs lose what lies outside the clip disc and keep their light.
    ImageBuf one = impulse(), tent;
    const Psf psf = [](double radius) { return smooth_footprint(2, radius); };
    CatEye far = cateye;
    far.centre = Imath::V2d(80.5, 0.5);
    REQUIRE(spread_cateye(tent, one, constant_radius(one.roi(), float(r)), psf, far));
    CHECK(channel_sum(tent, 0) == Approx(1.0).epsilon(1e-6));
    float p[4];
    tent.getpixel(-int(r / 2), 0, p);  // away from the centre, beyond the clip
    CHECK(p[0] == 0.0f);
    tent.getpixel(int(r / 2), 0, p);
    CHECK(p[0] > 0.0f);
}
