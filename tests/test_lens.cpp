// Lens effects through the library, as render_frame() renders a shot: a
// tilted plane of focus, a split diopter, the cat's eye.
#include <catch2/catch.hpp>

#include <cmath>
#include <utility>
#include <vector>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <defocus/render_frame.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using namespace OIIO;

namespace {

/// A flat RGBA+Z render, width x height, of a fine checkerboard: a ground
/// plane `height_m` below a level camera (focal 50 mm, filmback 36 mm)
/// below the horizon, a far sky above it; or, with height_m = 0, a wall
/// at `wall_m` filling the frame.
std::string checker_scene(const std::string& path, int width, int height, double height_m,
                          double wall_m = 0.0)
{
    ImageSpec spec(width, height, 5, TypeFloat);
    spec.channelnames = { "R", "G", "B", "A", "Z" };
    ImageBuf image(spec);
    const double focal_px = 50.0 / 36.0 * width;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const double v = (y + 0.5 - 0.5 * height) / focal_px;
            const float z = height_m == 0.0 ? float(wall_m)
                            : v > 0.02      ? float(height_m / v)
                                            : 1000.0f;
            const float c = ((x / 2 + y / 2) % 2) ? 0.9f : 0.1f;
            const float pixel[5] = { c, c, c, 1.0f, z };
            image.setpixel(x, y, pixel);
        }
    REQUIRE(image.write(path));
    return path;
}

}  // namespace

TEST_CASE("a tilted plane of focus puts the in-focus band on its predicted line")
{
    const int width = 240, height = 160;
    const std::string ground =
        checker_scene(scratch_dir("lens_focus_tilt") + "/ground.exr", width, height, 1.0);
    // Focused on the ground at pixel (120, 130), the plane turned 20 degrees
    // about the vertical axis, its right side away.
    const Settings focus_map = { { "focal", "50" }, { "fstop", "2" }, { "focus-at", "120,130" },
                                 { "focus-at-radius", "0" }, { "output", "focusmap" } };
    Settings tilted = focus_map;
    tilted.push_back({ "focus-tilt", "0,20" });
    const ImageBuf map = rendered(ground, tilted);
    // The ground at row y is at depth 1 / v, v = (y + 0.5 - 80) / f_px; the
    // plane through the focus point with normal (-tan 20°, 0, 1) meets the
    // ray of (u, v) at 1/z_f = (1 - tan 20° u) / (z_0 (1 - tan 20° u_0)). In
    // focus: v = 1/z_f.
    const double focal_px = 50.0 / 36.0 * width, t = std::tan(20.0 * M_PI / 180.0);
    const double u0 = (120.5 - 120.0) / focal_px, z0 = focal_px / (130.5 - 80.0);
    for (int x : { 10, 60, 120, 180, 230 }) {
        const double u = (x + 0.5 - 120.0) / focal_px;
        const double v = (1.0 - t * u) / (z0 * (1.0 - t * u0));
        const double predicted = v * focal_px + 80.0 - 0.5;
        // The focus map is greenest (G = 1 - |CoC| / 8 px) where it is sharp.
        int sharpest = -1;
        float best = -1.0f;
        for (int y = 90; y < height; ++y) {
            const float g = map.getchannel(x, y, 0, 1);
            if (g > best) {
                best = g;
                sharpest = y;
            }
        }
        INFO("column " << x << ": predicted row " << predicted << ", sharpest " << sharpest);
        CHECK(std::abs(sharpest - predicted) <= 1.0);
    }
    // Untilted, one row is in focus across the frame.
    const ImageBuf level = rendered(ground, focus_map);
    for (int x : { 10, 230 })
        CHECK(level.getchannel(x, 130, 0, 1) == Approx(1.0f).margin(0.05));
    // The tilt is recorded with the camera.
    const ParamValue* tilt = map.spec().find_attribute("defocus:focusTilt");
    REQUIRE(tilt);
    REQUIRE(tilt->type() == TypeDesc(TypeDesc::FLOAT, TypeDesc::VEC2));
    CHECK(static_cast<const float*>(tilt->data())[0] == 0.0f);
    CHECK(static_cast<const float*>(tilt->data())[1] == 20.0f);
}

TEST_CASE("a split diopter: each half matches a plain render at its distance")
{
    const int size = 160;
    const std::string wall =
        checker_scene(scratch_dir("lens_split_diopter") + "/wall.exr", size, size, 0.0, 3.0);
    const Settings common = { { "focal", "50" }, { "fstop", "2" }, { "edge", "extend" } };
    auto with = [&](Settings more) {
        more.insert(more.begin(), common.begin(), common.end());
        return more;
    };
    // Beyond the line from (0, 80) to (160, 80), the lower half, the
    // diopter focuses on the wall at 3 m; above it the lens is at 10 m.
    const ImageBuf split =
        rendered(wall, with({ { "focus", "10" }, { "split-diopter", "0,80,160,80:3" } }));
    const ImageBuf far = rendered(wall, with({ { "focus", "10" } }));
    const ImageBuf near = rendered(wall, with({ { "focus", "3" } }));
    // The wall at 3 m blurs to a CoC of about 8 px at focus 10: rows more
    // than that from the line see one half only.
    const int reach = 12;
    auto worst = [&](const ImageBuf& plain, int y0, int y1) {
        return ImageBufAlgo::compare(split, plain, 0.0f, 0.0f, ROI(0, size, y0, y1, 0, 1, 0, 4))
            .maxerror;
    };
    CHECK(worst(far, 0, 80 - reach) < 1e-5);
    CHECK(worst(near, 80 + reach, size) < 1e-5);
    // And the halves do differ: the upper one is blurred.
    CHECK(worst(near, 0, 80 - reach) > 0.1);
    // Keyframed: the diopter's focus moves over frames.
    const Settings keyed = with({ { "frames", "1-2" }, { "focus", "10" },
                                  { "split-diopter", "0,80,160,80:1:3,2:10" } });
    CHECK(rendered(wall, keyed, 1).spec().get_string_attribute("defocus:splitDiopter")
          == "0,80,160,80:3");
    CHECK(rendered(wall, keyed, 2).spec().get_string_attribute("defocus:splitDiopter")
          == "0,80,160,80:10");
    // A line of one point is an error.
    FrameResult result;
    std::string error;
    CHECK_FALSE(render_with(wall, with({ { "focus", "10" }, { "split-diopter", "5,5,5,5:3" } }), result,
                       error));
    CHECK(Strutil::contains(error, "two different points"));
}

TEST_CASE("the cat's eye clips bokeh towards the edges and keeps the light")
{
    ImageSpec spec(240, 136, 5, TypeFloat);
    spec.channelnames = { "R", "G", "B", "A", "Z" };
    ImageBuf field(spec);
    ImageBufAlgo::fill(field, { 0.0f, 0.0f, 0.0f, 0.0f, 1000.0f });
    const float light[5] = { 50, 50, 50, 1, 1000 };
    field.setpixel(120, 68, light);  // at the centre
    field.setpixel(12, 68, light);   // near the left edge
    const std::string file = scratch_dir("lens_cateye") + "/field.exr";
    REQUIRE(field.write(file));
    // A CoC of about 24 px: 0.05 m x 50/36 / 1.4 x 240 px x (1 - 1/1000).
    const Settings common = { { "focal", "50" }, { "fstop", "1.4" }, { "focus", "0.5" },
                              { "edge", "black" } };
    Settings cateye = common;
    cateye.push_back({ "cateye", "1" });
    cateye.push_back({ "window", "grown" });
    const ImageBuf plain = rendered(file, common), cut = rendered(file, cateye);
    CHECK(cut.spec().get_float_attribute("defocus:catEye") == 1.0f);
    // The same light; the side of the edge light away from the centre is
    // cut, the centre light is not.
    CHECK(channel_sum(cut, 0) == Approx(100.0).epsilon(1e-5));
    CHECK(plain.getchannel(12 - 9, 68, 0, 0) > 0.05f);
    CHECK(cut.getchannel(12 - 9, 68, 0, 0) == 0.0f);
    CHECK(plain.getchannel(120 - 9, 68, 0, 0) > 0.05f);
    CHECK(cut.getchannel(120 - 9, 68, 0, 0)
          == Approx(plain.getchannel(120 - 9, 68, 0, 0)).epsilon(0.05));
}

TEST_CASE("an in-focus range renders the depths it spans sharp")
{
    // The example's layers lie from 1 m to 60 m: a range over all of them
    // leaves the image as sharp as a lens that draws no blur.
    const ImageBuf ranged = rendered(example_scene(), { { "focus", "30" }, { "in-focus-range", "100" } });
    const ImageBuf no_blur = rendered(example_scene(), { { "focus", "30" }, { "max-blur", "0" } });
    const ImageBuf plain = rendered(example_scene(), { { "focus", "30" } });
    CHECK(ImageBufAlgo::compare(ranged, no_blur, 0.0f, 0.0f).maxerror < 1e-6);
    CHECK(ImageBufAlgo::compare(ranged, plain, 0.0f, 0.0f).maxerror > 0.05);
    CHECK(ranged.spec().get_float_attribute("defocus:inFocusRange") == 100.0f);
}
