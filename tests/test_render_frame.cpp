// One frame through the library, as every front end renders it: what is
// read (depth from files and channels, focus at a pixel), what bad pixels
// become, and what the frame's edges and depth units make of it.
#include <catch2/catch.hpp>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>

#include <defocus/frame_report.h>
#include <defocus/io/shot_file.h>
#include <defocus/render_frame.h>
#include <defocus/version.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using namespace OIIO;
using Strutil::fmt::format;

namespace {

/// No overscan and, at 250 m, a 17 px CoC; at 2.5 m, 3.4 px.
const Settings close_up = { { "focal", "50" }, { "fstop", "1" }, { "focus", "2" },
                            { "sensor", "3.6" } };

Settings with(Settings more)
{
    more.insert(more.begin(), close_up.begin(), close_up.end());
    return more;
}

}  // namespace

TEST_CASE("a uniform field stays uniform to the corners without overscan")
{
    // The edges are extended by default (and the frame says so); with the
    // edge black the corners lose most of their light.
    const std::string field = scratch_dir("frame_edges") + "/field.exr";
    write_uniform_image(field, { "R", "G", "B", "A", "Z" }, { 0.5f, 0.5f, 0.5f, 1, 250 }, 48, 48);
    FrameResult result;
    std::string error;
    REQUIRE(render_with(field, close_up, result, error));
    CHECK(Strutil::contains(result.edges, "edges: layers extended up to"));
    const auto extended = ImageBufAlgo::computePixelStats(result.image);
    const auto black = ImageBufAlgo::computePixelStats(rendered(field, with({ { "edge", "black" } })));
    for (int c = 0; c < 4; ++c) {
        const float expected = c == 3 ? 1.0f : 0.5f;
        CHECK(extended.min[c] == Approx(expected).epsilon(1e-5));
        CHECK(extended.max[c] == Approx(expected).epsilon(1e-5));
    }
    CHECK(black.min[3] < 0.5f);
}

TEST_CASE("Z in other units than metres is read with the depth scale")
{
    // The same scene with Z in metres and in centimetres.
    const std::string dir = scratch_dir("frame_depth_scale");
    write_uniform_image(dir + "/m.exr", { "R", "G", "B", "A", "Z" }, { 1, 0.5f, 0.25f, 1, 2.5f },
                        48, 48);
    write_uniform_image(dir + "/cm.exr", { "R", "G", "B", "A", "Z" }, { 1, 0.5f, 0.25f, 1, 250 },
                        48, 48);
    const ImageBuf metres = rendered(dir + "/m.exr", with({ { "window", "grown" } }));
    const ImageBuf centimetres = rendered(
        dir + "/cm.exr", with({ { "window", "grown" }, { "depth-scale", "0.01" } }));
    const ImageBuf unscaled = rendered(dir + "/cm.exr", with({ { "window", "grown" } }));
    CHECK(ImageBufAlgo::compare(centimetres, metres, 1e-6f, 1e-6f).nfail == 0);
    CHECK(ImageBufAlgo::compare(unscaled, metres, 1e-3f, 1e-3f).nfail > 0);
}

TEST_CASE("bad pixels are handled, counted and never reach the output")
{
    const std::string dir = scratch_dir("render_bad_pixels");
    // Pixels of NaN colour, bad depths, and transparent light.
    ImageSpec spec(8, 8, 5, TypeFloat);
    spec.channelnames = { "R", "G", "B", "A", "Z" };
    ImageBuf image(spec);
    ImageBufAlgo::fill(image, { 0.5f, 0.5f, 0.5f, 1.0f, 2.0f });
    const float nan_color[5] = { NAN, 0.5f, 0.5f, 1.0f, 2.0f };
    const float inf_alpha[5] = { 0.5f, 0.5f, 0.5f, INFINITY, 2.0f };
    const float zero_z[5] = { 0.5f, 0.5f, 0.5f, 1.0f, 0.0f };
    const float nan_z[5] = { 0.5f, 0.5f, 0.5f, 1.0f, NAN };
    const float negative_z[5] = { 0.5f, 0.5f, 0.5f, 1.0f, -3.0f };
    const float glow[5] = { 4.0f, 4.0f, 4.0f, 0.0f, 1e10f };
    image.setpixel(1, 1, nan_color);
    image.setpixel(2, 1, inf_alpha);
    image.setpixel(3, 3, zero_z);
    image.setpixel(4, 3, nan_z);
    image.setpixel(5, 3, negative_z);
    image.setpixel(6, 6, glow);
    const std::string in = dir + "/bad.exr";
    REQUIRE(image.write(in));
    const Settings camera = { { "focal", "50" }, { "fstop", "1.8" }, { "focus", "4" } };
    FrameResult result;
    std::string error;
    REQUIRE(render_with(in, camera, result, error));
    CHECK(result.fixed.nonfinite_color == 2);
    CHECK(result.fixed.bad_depth == 3);
    CHECK(result.fixed.transparent_light == 1);
    const std::string report = frame_report(result, shot_with({ in }, camera), "out.exr");
    CHECK(Strutil::contains(report, "2 with NaN/inf colour dropped"));
    CHECK(Strutil::contains(report, "3 with bad depth taken as infinitely far"));
    CHECK(Strutil::contains(report, "1 transparent with colour cleared"));
    CHECK(no_nan(result.image));
    const auto stats = ImageBufAlgo::computePixelStats(result.image);
    CHECK(stats.max[0] <= 0.5f + 1e-3f);  // the alpha-0 glow carried no light

    // Finite colour near float's limit overflowed the spreading sums into
    // NaN (disc, box, polygon): it is clamped to 1e30, and counted.
    ImageBuf hot(ImageSpec(48, 48, 5, TypeFloat));
    hot.specmod().channelnames = { "R", "G", "B", "A", "Z" };
    ImageBufAlgo::fill(hot, { 0.0f, 0.0f, 0.0f, 1.0f, 2.0f });
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 48; ++x)
            if ((x * 7 + y * 3) % 5 < 3) {
                const float v = (x + y) % 2 ? 3e38f : -3e38f;
                const float pixel[5] = { v, 3e38f, 1e30f, (x + y) % 3 ? 1.0f : 1.5f, 1e30f };
                hot.setpixel(x, y, pixel);
            }
    const float below_zero[5] = { 0.5f, 0.5f, 0.5f, -0.5f, 2.0f };
    hot.setpixel(0, 0, below_zero);
    REQUIRE(hot.write(dir + "/hot.exr"));
    for (const char* aperture : { "disc", "box", "polygon", "tent" }) {
        INFO(aperture);
        FrameResult hot_result;
        REQUIRE(render_with(dir + "/hot.exr",
                            { { "focal", "100" }, { "fstop", "1" }, { "focus", "0.5" },
                              { "aperture", aperture } },
                            hot_result, error));
        CHECK(hot_result.fixed.huge_color == 1382);
        CHECK(hot_result.fixed.transparent_light == 1);
        CHECK(no_nan(hot_result.image));
    }
}

TEST_CASE("focusing at a pixel takes the depth seen there, keyframed too")
{
    const std::string dir = scratch_dir("render_focus_at");
    const std::string scene = two_depth_scene(dir);
    auto focus_at = [&](const std::string& input, const std::string& at, int frame) {
        FrameResult result;
        std::string error;
        const bool ok = render_with(input, { { "focus-at", at } }, result, error, frame);
        INFO(error);
        REQUIRE(ok);
        return result.camera.focus_distance;
    };
    CHECK(focus_at(scene, "3,10", 1) == 2.0);
    // At x=10 the 5x5 window sees 10 pixels at 2 m and 15 at 6 m.
    CHECK(focus_at(scene, "1:3,10,3:17,10", 1) == 2.0);
    CHECK(focus_at(scene, "1:3,10,3:17,10", 2) == 6.0);
    CHECK(focus_at(scene, "1:3,10,3:17,10", 3) == 6.0);

    // The report prints a depth read from a float image with sensible
    // precision.
    const std::string at_1_7 = dir + "/at_1_7.exr";
    write_uniform_image(at_1_7, { "R", "G", "B", "A", "Z" }, { 1, 1, 1, 1, 1.7f });
    const Settings corner = { { "focus-at", "0,0" } };
    FrameResult result;
    std::string error;
    REQUIRE(render_with(at_1_7, corner, result, error));
    CHECK(Strutil::contains(frame_report(result, shot_with({ at_1_7 }, corner), "c.exr"),
                            " focus 1.7 sensor"));  // not 1.7000000476837158

    CHECK_FALSE(render_with(scene, { { "focus-at", "30,10" } }, result, error));
    CHECK(one_line_error(error, "outside the 20x20 display window"));
}

TEST_CASE("a render without alpha is opaque, and one without Z takes its depth from a file, "
          "a channel or a sequence")
{
    const std::string dir = scratch_dir("render_depth");
    const std::string scene_file = two_depth_scene(dir);
    const ImageBuf scene(scene_file);
    auto write_channels = [&](const std::string& name, const std::vector<int>& order,
                              const std::vector<std::string>& names) {
        const std::string path = dir + "/" + name;
        ImageBuf part = ImageBufAlgo::channels(scene, int(order.size()), order, {}, names);
        REQUIRE(part.write(path));
        return path;
    };
    const std::string rgbz = write_channels("rgbz.exr", { 0, 1, 2, 4 }, { "R", "G", "B", "Z" });
    const std::string rgba = write_channels("rgba.exr", { 0, 1, 2, 3 }, { "R", "G", "B", "A" });
    const std::string named = write_channels("named.exr", { 0, 1, 2, 3, 4 },
                                             { "R", "G", "B", "A", "P.depth" });
    for (int f : { 1, 2 })
        write_channels(format("depth.{:04}.exr", f), { 4 }, { "Y" });
    const std::string depth = dir + "/depth.0001.exr";
    for (int f : { 1, 2 })
        REQUIRE(Filesystem::copy(rgba, format("{}/rgba.{:04}.exr", dir, f)));
    const Settings look = { { "focal", "50" }, { "fstop", "1.4" }, { "focus", "2" },
                            { "sensor", "3.6" } };
    auto look_and = [&](Settings more) {
        more.insert(more.begin(), look.begin(), look.end());
        return more;
    };
    auto notes = [](const FrameResult& result) { return Strutil::join(result.notes, "\n"); };
    auto same_as = [&](const FrameResult& result) {
        return ImageBufAlgo::compare(result.image, rendered(scene_file, look), 1e-6f, 1e-6f).nfail
               == 0;
    };

    FrameResult result;
    std::string error;
    REQUIRE(render_with(rgbz, look, result, error));
    CHECK(Strutil::contains(notes(result), "rgbz.exr: no alpha channel, taken as opaque"));
    CHECK(same_as(result));
    REQUIRE(render_with(rgba, look_and({ { "depth", depth } }), result, error));
    CHECK(Strutil::contains(notes(result), "depth from " + depth));
    CHECK(same_as(result));
    REQUIRE(render_with(named, look_and({ { "depth", "P.depth" } }), result, error));
    CHECK(same_as(result));
    // A depth sequence beside a colour sequence, frame by frame.
    REQUIRE(render_with(dir + "/rgba.#.exr", look_and({ { "depth", dir + "/depth.#.exr" } }), result,
                        error, 2));
    CHECK(same_as(result));
    // A .dof keeps a depth file relative to itself.
    REQUIRE(save_shot(shot_with({ rgba }, look_and({ { "depth", depth } })), dir + "/shot.dof",
                      error));
    std::string dof;
    REQUIRE(Filesystem::read_text_file(dir + "/shot.dof", dof));
    CHECK(Strutil::contains(dof, "\"depth\": \"depth.0001.exr\""));
    Shot loaded;
    REQUIRE(load_shot(dir + "/shot.dof", loaded, error));
    REQUIRE(render_shot(loaded, result, error));
    CHECK(same_as(result));

    CHECK_FALSE(render_with(rgba, look, result, error));
    CHECK(one_line_error(error, "rgba.exr: part 0 has no Z channel (channels: R,G,B,A): give its "
                                "depth with --depth FILE or --depth CHANNEL"));
}

TEST_CASE("the camera a render recorded in its header is used frame by frame, settings override")
{
    const std::string dir = scratch_dir("render_camera_from_file");
    // A focus pull baked into the render: 2, 4, 6 m over three frames, with
    // OpenEXR's standard focus and aperture and Arnold's focal length.
    for (int f = 1; f <= 3; ++f) {
        ImageSpec spec(16, 16, 5, TypeFloat);
        spec.channelnames = { "R", "G", "B", "A", "Z" };
        spec.attribute("focus", float(2 * f));
        spec.attribute("FNumber", 2.8f);  // OpenImageIO's name for `aperture`
        spec.attribute("CameraFocalLength", 85.0f);
        ImageBuf image(spec);
        ImageBufAlgo::fill(image, { 0.5f, 0.5f, 0.5f, 1.0f, 3.0f });
        REQUIRE(image.write(format("{}/pull.{:04}.exr", dir, f)));
    }
    const std::string pull = dir + "/pull.#.exr";
    FrameResult result;
    std::string error;
    for (int f = 1; f <= 3; ++f) {
        INFO("frame " << f);
        REQUIRE(render_with(pull, {}, result, error, f));
        CHECK(result.camera.focus_distance == 2.0 * f);
        CHECK(result.camera.fstop == Approx(2.8));
        CHECK(result.camera.focal_length_mm == 85.0);
    }
    CHECK(Strutil::contains(frame_report(result, shot_with({ pull }, {}), "out.exr"),
                            "camera values from: focal file: CameraFocalLength, f-number file: "
                            "FNumber, focus file: focus, sensor default"));
    // Settings win; off reads nothing.
    REQUIRE(render_with(pull, { { "focus", "5" } }, result, error, 2));
    CHECK(result.camera.focus_distance == 5.0);
    CHECK(result.camera.focal_length_mm == 85.0);
    const Settings off = { { "camera-from-file", "off" } };
    REQUIRE(render_with(pull, { { "focus", "5" }, off.front() }, result, error, 2));
    CHECK(result.camera.focal_length_mm == Camera().focal_length_mm);
    CHECK_FALSE(render_with(pull, off, result, error, 2));
    CHECK(one_line_error(error, "or --focus-at X,Y is required"));
}

TEST_CASE("a frame whose header gives no focus distance is refused before its pixels are read")
{
    // A header without pixels: were they read first, the error would be
    // the missing pixels (or, on a 4K frame, a second and 540 MB later,
    // the focus).
    const std::string dir = scratch_dir("render_no_focus");
    const std::string file = dir + "/header_only.exr";
    write_exr_header_only(file, 64, 48);
    FrameResult result;
    std::string error;
    CHECK_FALSE(render_with(file, {}, result, error));
    CHECK(one_line_error(error, "header_only.exr: no focus distance: give --focus DIST"));
    // With a focus, the pixels are read and found missing.
    CHECK_FALSE(render_with(file, { { "focus", "3" } }, result, error));
    CHECK(one_line_error(error, "header_only.exr: corrupt or truncated"));
}

TEST_CASE("a result keeps the software that made its input, and adds a line to its history")
{
    const std::string dir = scratch_dir("render_provenance");
    ImageBuf image(read_image(two_depth_scene(dir)));
    image.specmod().attribute("Software", "Blender 3.4");
    image.specmod().attribute("Exif:ImageHistory", "rendered");
    const std::string input = dir + "/rendered.exr";
    REQUIRE(image.write(input));
    const std::string ours = "defocus " + std::string(version());
    FrameResult once, twice;
    std::string error;
    REQUIRE(render_with(input, { { "fstop", "2.8" }, { "focus", "3" } }, once, error));
    CHECK(once.image.spec().get_string_attribute("Software") == "Blender 3.4; " + ours);
    CHECK(once.image.spec().get_string_attribute("Exif:ImageHistory")
          == "rendered\n" + ours + ": " + input + " --focus 3 --fstop 2.8");
    // Defocused again: one more line, the software named once.
    REQUIRE(once.image.write(dir + "/once.exr"));
    REQUIRE(render_with(dir + "/once.exr", { { "depth", input }, { "focus", "2" } }, twice,
                        error));
    CHECK(twice.image.spec().get_string_attribute("Software") == "Blender 3.4; " + ours);
    const std::vector<std::string> lines =
        Strutil::splits(twice.image.spec().get_string_attribute("Exif:ImageHistory"), "\n");
    REQUIRE(lines.size() == 3);
    CHECK_THAT(lines[2], Catch::StartsWith(ours + ": " + dir + "/once.exr"));
    CHECK_THAT(lines[2], Catch::EndsWith("--depth " + input + " --focus 2"));
    // Each setting as the command takes it: switches by their flag, a mask
    // with its file.
    const std::string mask = std::string(EXAMPLES_DIR) + "/psf/blades7.exr";
    REQUIRE(render_with(input,
                        { { "focus", "3" }, { "aperture", "mask:" + mask },
                          { "window", "display" }, { "deep", "on" } },
                        once, error));
    CHECK_THAT(once.image.spec().get_string_attribute("Exif:ImageHistory"),
               Catch::EndsWith(" --focus 3 --aperture mask:" + mask + " --deep --crop"));
}

TEST_CASE("slicing a flat render stops when the render is cancelled")
{
    // Python's Ctrl-C waited for the slicing of a 4K render (6 s): only
    // the stages after it asked whether to go on.
    const std::string dir = scratch_dir("render_frame_slice_cancelled");
    const Shot shot = shot_with({ two_depth_scene(dir) }, { { "focal", "50" },
                                                             { "fstop", "1.4" },
                                                             { "focus", "3" } });
    ShotAssets assets;
    std::string error;
    REQUIRE(read_shot_assets(shot, assets, error));
    std::string last_stage;
    FrameResult result;
    CHECK_FALSE(render_frame(shot, 1, assets, result, error, [&](const char* stage) {
        if (stage)
            last_stage = stage;
        return stage != nullptr;  // cancelled as soon as a stage asks to go on
    }));
    CHECK_THAT(error, Catch::EndsWith(": cancelled"));
    CHECK(last_stage == "slice");
}
