// The hybrid method: highlights spread with a PSF image, the rest fast.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>

#include <defocus/color/color.h>
#include <defocus/composite/defocus_layers.h>
#include <defocus/io/aperture_files.h>
#include <defocus/spread/hybrid.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using OIIO::ImageBuf;
using OIIO::ROI;

namespace {

const std::string shipped_psf = std::string(EXAMPLES_DIR) + "/psf/";

/// A wall at depth 10 (grey, or transparent) with one bright highlight in
/// its middle, seen by the synthetic camera focused at 1 (CoC 30 px).
Scene highlight_scene(float wall_alpha = 1.0f)
{
    Scene scene;
    scene.spec = OIIO::ImageSpec(120, 80, 4, OIIO::TypeFloat);
    const ROI frame(0, 120, 0, 80);
    Layer wall { "wall", zero_image(frame, 4), zero_image(frame, 1) };
    OIIO::ImageBufAlgo::fill(wall.color, { 0.1f * wall_alpha, 0.1f * wall_alpha,
                                           0.1f * wall_alpha, wall_alpha });
    OIIO::ImageBufAlgo::fill(wall.depth, { 10.0f });
    const float light[4] = { 50.0f, 50.0f, 50.0f, 1.0f };
    wall.color.setpixel(60, 40, light);
    wall.color.specmod().alpha_channel = 3;
    scene.layers.push_back(std::move(wall));
    return scene;
}

}  // namespace

TEST_CASE("visible bokeh: a highlight against its surroundings, not an even area")
{
    Scene scene = highlight_scene();
    ImageBuf radius;
    REQUIRE(coc_radius(radius, scene.layers[0].depth,
                       CircleOfConfusion(synthetic_camera(1.0), ROI(0, 120, 0, 120))));
    const std::vector<uint8_t> slow = visible_bokeh(scene.layers[0].color, radius, { 4.0, luma_weights(nullptr) });
    CHECK(std::count(slow.begin(), slow.end(), uint8_t(1)) == 1);
    CHECK(slow[40 * 120 + 60] == 1);
    // In focus, nothing's bokeh is visible.
    REQUIRE(coc_radius(radius, scene.layers[0].depth,
                       CircleOfConfusion(synthetic_camera(10.0), ROI(0, 120, 0, 120))));
    const std::vector<uint8_t> sharp = visible_bokeh(scene.layers[0].color, radius, { 4.0, luma_weights(nullptr) });
    CHECK(std::count(sharp.begin(), sharp.end(), uint8_t(1)) == 0);
}

TEST_CASE("visible bokeh weighs colour by the luminance weights it is given")
{
    // A blue highlight, 3x the grey wall in blue alone: 1.1x its luminance
    // by Rec.709's weights (blue counts 7%), 3x when only blue counts.
    Scene scene = highlight_scene();
    const float blue[4] = { 0.1f, 0.1f, 0.3f, 1.0f };
    scene.layers[0].color.setpixel(60, 40, blue);
    ImageBuf radius;
    REQUIRE(coc_radius(radius, scene.layers[0].depth,
                       CircleOfConfusion(synthetic_camera(1.0), ROI(0, 120, 0, 120))));
    auto selected = [&](const Imath::V3d& luma) {
        const std::vector<uint8_t> s = visible_bokeh(scene.layers[0].color, radius, { 2.0, luma });
        return std::count(s.begin(), s.end(), uint8_t(1));
    };
    CHECK(selected(luma_weights(nullptr)) == 0);
    CHECK(selected(Imath::V3d(0.0, 0.0, 1.0)) == 1);
}

TEST_CASE("visible bokeh selects exactly the pixels a direct window mean selects")
{
    // Bright and dim pixels at random over an image tall enough to be cut
    // into bands, radii from 0 to 14 px across it, a data window off the
    // origin: every pixel's verdict against the mean summed directly.
    const ROI roi(-7, 233, 5, 415, 0, 1, 0, 4);
    ImageBuf color = zero_image(roi, 4), radius = zero_image(ROI(-7, 233, 5, 415, 0, 1, 0, 1), 1);
    uint32_t state = 12345;
    auto random = [&] {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) * 0x1p-24f;
    };
    for (int y = roi.ybegin; y < roi.yend; ++y)
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const float v = random() < 0.03f ? 40.0f * random() : random() < 0.2f ? 0.0f : random();
            const float c[4] = { v, 0.5f * v, 2.0f * v, 1.0f };
            color.setpixel(x, y, c);
            const float r = 14.0f * float(x - roi.xbegin) / roi.width();
            radius.setpixel(x, y, &r);
        }
    const Imath::V3d luma = luma_weights(nullptr);
    const double threshold = 2.0;
    const std::vector<uint8_t> selected = visible_bokeh(color, radius, { threshold, luma }, 2);
    auto luminance = [&](int x, int y) {
        float c[4];
        color.getpixel(x, y, c);
        return luma.x * c[0] + luma.y * c[1] + luma.z * c[2];
    };
    int highlights = 0, differ = 0;
    for (int y = roi.ybegin; y < roi.yend; ++y)
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            float r;
            radius.getpixel(x, y, &r);
            const double l = luminance(x, y);
            bool expect = false;
            if (r >= 1.0f && l > 0.0) {
                const int k = int(std::ceil(r));
                double sum = 0.0;
                int n = 0;
                const int x0 = std::max(roi.xbegin, x - k), x1 = std::min(roi.xend, x + k + 1);
                const int y0 = std::max(roi.ybegin, y - k), y1 = std::min(roi.yend, y + k + 1);
                for (int j = y0; j < y1; ++j)
                    for (int i = x0; i < x1; ++i, ++n)
                        sum += luminance(i, j);
                expect = l > threshold * sum / n;
            }
            highlights += expect;
            differ += expect
                      != bool(selected[size_t(y - roi.ybegin) * roi.width() + (x - roi.xbegin)]);
        }
    CHECK(highlights > 1000);
    CHECK(differ == 0);
}

TEST_CASE("a PSF image is scaled to the CoC and normalised")
{
    PsfImage psf;
    std::string error;
    REQUIRE(read_psf_image(shipped_psf + "disc_rim.exr", luma_weights(nullptr), psf, error));
    for (double r : { 0.5, 3.0, 7.5, 20.0 }) {
        const Footprint fp = psf.footprint(r);
        double sum = 0.0;
        for (double w : fp.weights)
            sum += w;
        CHECK(sum == Approx(1.0).epsilon(1e-9));
        CHECK(fp.width == (r < 1.0 ? 1 : 2 * int(std::ceil(r)) + 1));
    }
    // The rim is brighter than the centre; outside the disc, nothing.
    const Footprint fp = psf.footprint(20.0);
    const int c = -fp.x0;
    CHECK(fp.at(c + 19, c) > 1.5 * fp.at(c, c));
    CHECK(fp.at(c + 15, c + 15) == 0.0);
    PsfImage missing;
    CHECK_FALSE(read_psf_image(shipped_psf + "nope.exr", luma_weights(nullptr), missing, error));
    CHECK_THAT(error, Catch::Contains("nope.exr"));
}

TEST_CASE("the hybrid method spreads highlights with the PSF image and keeps energy")
{
    const Camera camera = synthetic_camera(1.0);
    SpreadOptions spread;
    spread.aperture.shape = ApertureShape::Box;
    auto psf = std::make_shared<PsfImage>();
    std::string error;
    REQUIRE(read_psf_image(shipped_psf + "disc_rim.exr", luma_weights(nullptr), *psf, error));
    ApertureImages images;
    images.psf = psf;
    // A lone highlight (on a transparent wall, so no coverage overlaps).
    ImageBuf out;
    std::vector<LayerReport> report;
    REQUIRE(defocus_layers(out, layered_scene(highlight_scene(0.0f), camera), camera, spread,
                           images, OutputWindow::Input, &report));
    CHECK(report[0].psf_pixels == 1);
    CHECK(channel_sum(out, 0) == Approx(50.0).epsilon(1e-5));
    CHECK(channel_sum(out, 3) == Approx(1.0).epsilon(1e-5));
    // Its bokeh is the PSF's: a bright rim at r = 15 px around (60, 40), a
    // dimmer inside, and round (a box would reach the corner).
    float rim[4], inside[4], corner[4];
    out.getpixel(60 + 14, 40, rim);
    out.getpixel(60 + 5, 40, inside);
    out.getpixel(60 + 12, 40 + 12, corner);
    CHECK(rim[0] > 1.5f * inside[0]);
    CHECK(inside[0] > 0.0f);
    CHECK(corner[0] == 0.0f);
    // On the grey wall, the wall is spread the fast way around it (less
    // the highlight pixel's own 1/730 share of grey).
    REQUIRE(defocus_layers(out, layered_scene(highlight_scene(), camera), camera, spread,
                           images, OutputWindow::Input, &report));
    out.getpixel(60 + 12, 40 + 12, corner);
    CHECK(corner[0] == Approx(0.1f).margin(2e-4));
}

TEST_CASE("the shipped PSF images are the ones our generator makes")
{
    const std::string dir = scratch_dir("psf_images");
    std::string log;
    REQUIRE(run(std::string(MAKE_PSF_IMAGES_BIN) + " " + dir, log) == 0);
    for (const char* name : { "disc_rim.exr", "blades7.exr" }) {
        INFO(name);
        const ImageBuf made = read_image(dir + "/" + name), shipped = read_image(shipped_psf + name);
        REQUIRE(made.initialized());
        REQUIRE(shipped.initialized());
        CHECK(worst_relative_error(made, shipped, 0.0, 1e-7) <= 1.0);
    }
}
