// Renders as studios write them: depth of other kinds than planar Z,
// anamorphic plates, clipped highlights, and the picture of the layering.
#include <catch2/catch.hpp>

#include <cmath>
#include <functional>
#include <string>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>

#include <defocus/color/bloom.h>
#include <defocus/render_frame.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using namespace OIIO;
using Strutil::fmt::format;

namespace {

const Settings lens = { { "focal", "50" }, { "fstop", "2" }, { "sensor", "36" } };

Settings with(Settings settings, const Settings& more)
{
    settings.insert(settings.end(), more.begin(), more.end());
    return settings;
}

/// A 40x30 flat render: a grey half at 2 m, a blue half at 6 m, a thin
/// white bar at 1 m; its Z rewritten by `depth_of(z, x, y)`, and its header
/// declaring `declared` as the depth's kind ("" = none).
std::string depth_scene(const std::string& path, const std::function<float(float, int, int)>& depth_of,
                        const std::string& declared = "")
{
    ImageSpec spec = rgbaz_spec(40, 30);
    if (!declared.empty())
        spec.attribute(depth_kind_attribute, declared);
    ImageBuf image(spec);
    for (ImageBuf::Iterator<float> it(image); !it.done(); ++it) {
        const float z = it.x() >= 18 && it.x() < 21 ? 1.0f : it.x() < 20 ? 2.0f : 6.0f;
        const float c = z == 1.0f ? 1.0f : z == 2.0f ? 0.5f : 0.2f;
        const float pixel[5] = { c, c, z == 6.0f ? 0.8f : c, 1.0f, depth_of(z, it.x(), it.y()) };
        for (int ch = 0; ch < 5; ++ch)
            it[ch] = pixel[ch];
    }
    REQUIRE(image.write(path));
    return path;
}

FrameResult render_ok(const std::string& input, const Settings& settings)
{
    FrameResult result;
    std::string error;
    const bool ok = render_with(input, settings, result, error);
    INFO(error);
    REQUIRE(ok);
    return result;
}

}  // namespace

TEST_CASE("depth as 1/z, ray distance or CoC renders as planar Z does, kind from flag or header")
{
    const std::string dir = scratch_dir("depth_kinds");
    const Settings camera = with(lens, { { "focus", "3" } });
    const std::string planar = depth_scene(dir + "/z.exr", [](float z, int, int) { return z; });
    const ImageBuf expected = render_ok(planar, camera).image;

    // 1/z, said by the header: -v names where the kind came from.
    const FrameResult inverse = render_ok(
        depth_scene(dir + "/inverse.exr", [](float z, int, int) { return 1.0f / z; }, "inverse"),
        camera);
    CHECK(inverse.depth.kind == DepthKind::Inverse);
    CHECK(inverse.depth.origin == "file: defocus:depthKind");
    CHECK(largest_difference(inverse.image, expected) < 1e-5f);
    // layerize writes planar Z, and so no longer says the depth is 1/z.
    std::string log;
    REQUIRE(run(format("{} {}/inverse.exr -o {}/layers.exr --focal 50 --fstop 2 --focus 3",
                       LAYERIZE_BIN, dir, dir),
                log) == 0);
    CHECK(read_spec(dir + "/layers.exr").get_string_attribute(depth_kind_attribute).empty());
    CHECK(largest_difference(render_ok(dir + "/layers.exr", camera).image, expected) < 1e-4f);
    // The flag wins over the header: the same file read as planar is wrong.
    const FrameResult overridden = render_ok(dir + "/inverse.exr",
                                             with(camera, { { "depth-kind", "z" } }));
    CHECK(largest_difference(overridden.image, expected) > 0.1f);

    // Distance along the ray from the optical centre (40x30: 20,15).
    const double focal_px = 50.0 / 36.0 * 40;
    auto distance = [&](float z, int x, int y) {
        const double u = (x + 0.5 - 20) / focal_px, v = (y + 0.5 - 15) / focal_px;
        return float(z * std::sqrt(1 + u * u + v * v));
    };
    const FrameResult along_rays = render_ok(depth_scene(dir + "/distance.exr", distance),
                                             with(camera, { { "depth-kind", "distance" } }));
    CHECK(largest_difference(along_rays.image, expected) < 1e-5f);

    // The CoC the camera gives each depth: no camera needed.
    Camera cam;
    cam.focal_length_mm = 50;
    cam.fstop = 2;
    cam.focus_distance = 3;
    const CircleOfConfusion coc(cam, ROI(0, 40, 0, 30));
    const FrameResult from_coc = render_ok(
        depth_scene(dir + "/coc.exr",
                    [&](float z, int x, int y) { return float(coc.diameter(z, x, y)); }),
        { { "depth-kind", "coc" } });
    CHECK(command_line_words(from_coc.depth.origin) == "--depth-kind");
    CHECK(largest_difference(from_coc.image, expected) < 1e-4f);
}

TEST_CASE("the coc AOV of one render is the depth of the next, with no camera")
{
    const std::string dir = scratch_dir("coc_aov_depth");
    const Settings camera = with(lens, { { "focus", "3" } });
    const std::string planar = depth_scene(dir + "/z.exr", [](float z, int, int) { return z; });
    const FrameResult first = render_ok(planar, with(camera, { { "aov", "coc" } }));
    REQUIRE(first.image.write(dir + "/with_coc.exr"));
    const FrameResult again = render_ok(dir + "/with_coc.exr", { { "depth", "coc" } });
    CHECK(again.depth.kind == DepthKind::Coc);
    CHECK(command_line_words(again.depth.origin) == "--depth coc: the coc AOV's channel");
    CHECK(no_nan(again.image));
}

TEST_CASE("a deep image's samples with 1/z depth render as with planar Z")
{
    // Each pixel: a half-covering sample at 2 m (on the left half) over an
    // opaque one at 6 m, Z and ZBack rewritten by `depth_of`.
    const std::string dir = scratch_dir("deep_depth_kinds");
    auto deep_scene = [&](const std::string& name, float (*depth_of)(float)) {
        ImageSpec spec(40, 30, 6, TypeFloat);
        spec.channelnames = { "R", "G", "B", "A", "Z", "ZBack" };
        spec.deep = true;
        DeepData data(spec);
        for (int y = 0; y < 30; ++y)
            for (int x = 0; x < 40; ++x) {
                const int64_t p = int64_t(y) * 40 + x;
                const bool near = x < 20;
                data.set_samples(p, near ? 2 : 1);
                int s = 0;
                if (near) {
                    for (int c = 0; c < 6; ++c)
                        data.set_deep_value(p, c, s, c < 4 ? 0.5f : depth_of(2.0f));
                    ++s;
                }
                const float wall[6] = { 0.1f, 0.4f, 0.2f, 1.0f, depth_of(6.0f), depth_of(6.0f) };
                for (int c = 0; c < 6; ++c)
                    data.set_deep_value(p, c, s, wall[c]);
            }
        const std::string path = dir + "/" + name + ".exr";
        auto out = ImageOutput::create(path);
        REQUIRE(out->open(path, spec));
        REQUIRE(out->write_deep_image(data));
        REQUIRE(out->close());
        return path;
    };
    const Settings camera = with(lens, { { "focus", "3" } });
    const ImageBuf planar
        = render_ok(deep_scene("z", [](float z) { return z; }), camera).image;
    const ImageBuf inverse = render_ok(deep_scene("inverse", [](float z) { return 1.0f / z; }),
                                       with(camera, { { "depth-kind", "inverse" } }))
                                 .image;
    CHECK(largest_difference(inverse, planar) < 1e-5f);
}

TEST_CASE("a holdout whose header says its depth is 1/z holds out as its planar twin")
{
    const std::string dir = scratch_dir("holdout_depth_kind");
    const Settings camera = with(lens, { { "focus", "3" } });
    const std::string scene = depth_scene(dir + "/z.exr", [](float z, int, int) { return z; });
    auto holdout = [&](const std::string& name, float depth, const std::string& declared) {
        ImageSpec spec = rgbaz_spec(40, 30);
        if (!declared.empty())
            spec.attribute(depth_kind_attribute, declared);
        ImageBuf card(spec);
        ImageBufAlgo::fill(card, { 0.0f, 0.0f, 0.0f, 0.0f, depth });
        ImageBufAlgo::fill(card, { 0.2f, 0.2f, 0.2f, 1.0f, depth }, ROI(0, 25, 0, 30));
        REQUIRE(card.write(dir + "/" + name));
        return dir + "/" + name;
    };
    const ImageBuf planar
        = render_ok(scene, with(camera, { { "holdout", holdout("planar.exr", 4.0f, "") } })).image;
    const ImageBuf inverse = render_ok(
        scene, with(camera, { { "holdout", holdout("inverse.exr", 0.25f, "inverse") } })).image;
    CHECK(largest_difference(inverse, planar) < 1e-6f);
    // Read as metres, 0.25 m would hold out everything behind it.
    const ImageBuf wrong = render_ok(
        scene, with(camera, { { "holdout", holdout("untagged.exr", 0.25f, "") } })).image;
    CHECK(largest_difference(wrong, planar) > 0.05f);
    FrameResult result;
    std::string error;
    CHECK_FALSE(render_with(scene, with(camera, { { "holdout", holdout("coc.exr", 4.0f, "coc") } }),
                            result, error));
    CHECK(one_line_error(error, "coc.exr: a holdout's depth must be a distance"));
}

TEST_CASE("depth kinds: nonsense depth and a focus on a CoC map are one-line errors")
{
    const std::string dir = scratch_dir("depth_kind_errors");
    FrameResult result;
    std::string error;
    const std::string negative = depth_scene(
        dir + "/negative.exr", [](float z, int x, int) { return x == 3 ? -1.0f : 1.0f / z; });
    CHECK_FALSE(render_with(negative, with(lens, { { "focus", "3" }, { "depth-kind", "inverse" } }),
                            result, error));
    CHECK(one_line_error(error, "negative.exr: --depth-kind inverse (--depth-kind): 30 pixels "
                                "or samples hold negative or NaN inverse depth (the first at 3,0"));

    const std::string map = depth_scene(dir + "/map.exr", [](float, int, int) { return 4.0f; },
                                        "coc");
    for (const Settings& focused : { Settings { { "focus", "3" } },
                                     Settings { { "focus-tilt", "5,0" }, { "focus", "3" } },
                                     Settings { { "depth-scale", "0.01" } } }) {
        CHECK_FALSE(render_with(map, focused, result, error));
        INFO(error);
        CHECK(one_line_error(error, "has no meaning for a depth that is a CoC map (--depth-kind coc)"));
    }
    // Said by the flag, the shot is refused before any file is read.
    Shot shot = shot_with({ dir + "/none.exr" }, { { "depth-kind", "coc" }, { "focus", "3" } });
    CHECK_FALSE(check_shot(shot, error));
    CHECK(one_line_error(error, "--focus has no meaning for a depth that is a CoC map"));
    // The map alone renders, every pixel blurred by its own CoC of 4 px.
    CHECK(render_with(map, {}, result, error));
}

TEST_CASE("bloom lifts a display-referred plate's clipped highlights, and only them")
{
    // An sRGB PNG: a clipped white square on grey, all of it 20 m away,
    // the lens focused at 1 m.
    const std::string dir = scratch_dir("bloom");
    ImageSpec spec(64, 64, 3, TypeUInt8);
    ImageBuf plate(spec);
    ImageBufAlgo::fill(plate, { 0.5f, 0.5f, 0.5f });
    ImageBufAlgo::fill(plate, { 1.0f, 1.0f, 1.0f }, ROI(29, 35, 29, 35));
    REQUIRE(plate.write(dir + "/plate.png"));
    write_uniform_image(dir + "/depth.exr", { "Z" }, { 20.0f }, 64, 64, TypeFloat);
    const Settings settings = with(lens, { { "focus", "1" }, { "depth", dir + "/depth.exr" },
                                           { "tocolorspace", "lin_rec709" } });
    auto brightest = [](const ImageBuf& image) {
        return ImageBufAlgo::computePixelStats(image).max[0];
    };
    const FrameResult plain = render_ok(dir + "/plate.png", settings);
    const FrameResult bloomed = render_ok(dir + "/plate.png", with(settings, { { "bloom", "0.9,4" } }));
    WARN("brightest pixel: " << brightest(plain.image) << " plain, " << brightest(bloomed.image)
                             << " with --bloom 0.9,4");
    CHECK(brightest(bloomed.image) >= 1.5f * brightest(plain.image));
    CHECK(plain.bloom.empty());
    CHECK(bloomed.bloom == "bloom: 36 pixels or samples lifted, those above 0.9 by 4x");
    // The grey far from the square is not touched.
    float far_plain[3], far_bloomed[3];
    plain.image.getpixel(5, 5, far_plain, 3);
    bloomed.image.getpixel(5, 5, far_bloomed, 3);
    CHECK(far_plain[0] == far_bloomed[0]);
    // A threshold above every pixel changes no bit.
    const FrameResult above = render_ok(dir + "/plate.png", with(settings, { { "bloom", "2,4" } }));
    CHECK(largest_difference(above.image, plain.image) == 0.0f);
}

TEST_CASE("bloom's ramp is smooth and reaches the gain at the threshold")
{
    const Bloom bloom { 0.5, 3.0 };
    CHECK(bloom.factor(0.2, 0.3, 0.44) == 1.0);
    CHECK(bloom.factor(0.5, 0.1, 0.1) == Approx(3.0));
    CHECK(bloom.factor(0.1, 7.0, 0.1) == Approx(3.0));
    CHECK(bloom.factor(0.475, 0.0, 0.0) == Approx(2.0));  // half way up the ramp
    double previous = 1.0;
    for (double v = 0.4; v <= 0.6; v += 0.001) {
        const double f = bloom.factor(v, v, v);
        CHECK(f >= previous);
        CHECK(f - previous < 0.1);  // the steepest: 1.5 x 2 / 0.05 per unit, 0.06 a step
        previous = f;
    }
}

namespace {

/// A 256x256 plate of black at 20 m with one bright pixel in its middle,
/// its pixels `pixel_aspect` times as wide as tall.
std::string point_plate(const std::string& path, float pixel_aspect)
{
    ImageSpec spec = rgbaz_spec(256, 256);
    spec.attribute("PixelAspectRatio", pixel_aspect);
    ImageBuf plate(spec);
    ImageBufAlgo::fill(plate, { 0.0f, 0.0f, 0.0f, 1.0f, 20.0f });
    ImageBufAlgo::fill(plate, { 100.0f, 100.0f, 100.0f, 1.0f, 20.0f }, ROI(128, 129, 128, 129));
    REQUIRE(plate.write(path));
    return path;
}

/// The light's centroid and spread across and down, in the desqueezed
/// image's units (a column `pixel_aspect` wide, a row 1 high).
struct Bokeh {
    Imath::V2d centre, spread;
};

Bokeh desqueezed_bokeh(const ImageBuf& image, double pixel_aspect)
{
    double sum = 0, sx = 0, sy = 0, sxx = 0, syy = 0;
    for (ImageBuf::ConstIterator<float> it(image); !it.done(); ++it) {
        const double w = it[0], x = (it.x() + 0.5) * pixel_aspect, y = it.y() + 0.5;
        sum += w;
        sx += w * x;
        sy += w * y;
        sxx += w * x * x;
        syy += w * y * y;
    }
    const Imath::V2d centre(sx / sum, sy / sum);
    return { centre, { std::sqrt(sxx / sum - centre.x * centre.x),
                       std::sqrt(syy / sum - centre.y * centre.y) } };
}

/// The width over the height of the light in channel R, in the file's
/// pixels: the ratio of its standard deviations across and down.
double width_over_height(const ImageBuf& image)
{
    const Imath::V2d spread = desqueezed_bokeh(image, 1.0).spread;
    return spread.x / spread.y;
}

}  // namespace

TEST_CASE("an anamorphic plate's bokeh is round on the desqueezed image")
{
    const std::string dir = scratch_dir("pixel_aspect");
    const Settings settings = with(lens, { { "focus", "1" } });
    const FrameResult squeezed = render_ok(point_plate(dir + "/squeezed.exr", 2.0f), settings);
    const FrameResult square = render_ok(point_plate(dir + "/square.exr", 1.0f), settings);
    const double ratio = width_over_height(squeezed.image);
    WARN("bokeh width over height: " << ratio << " (pixel aspect 2), "
                                     << width_over_height(square.image) << " (1)");
    CHECK(ratio == Approx(0.5).margin(0.1));
    CHECK(width_over_height(square.image) == Approx(1.0).margin(0.02));
    CHECK(squeezed.camera.pixel_aspect == 2.0);
    // The light is kept, and its height is the square plate's: the lens
    // blurs a point by as many rows either way.
    CHECK(channel_sum(squeezed.image, 0) == Approx(100.0).epsilon(1e-4));
    CHECK(desqueezed_bokeh(squeezed.image, 2.0).spread.y
          == Approx(desqueezed_bokeh(square.image, 1.0).spread.y).epsilon(0.05));
    // --aspect, the lens's own squeeze, multiplies in.
    const double lens_squeezed = width_over_height(
        render_ok(dir + "/squeezed.exr", with(settings, { { "aspect", "2" } })).image);
    CHECK(lens_squeezed == Approx(1.0).margin(0.1));
    // The box, the polygon and the mask are squeezed alike.
    const std::string mask = "mask:" + std::string(EXAMPLES_DIR) + "/psf/blades7.exr";
    for (const std::string& aperture : { std::string("box"), std::string("polygon"), mask }) {
        INFO(aperture);
        CHECK(width_over_height(render_ok(dir + "/squeezed.exr",
                                          with(settings, { { "aperture", aperture } }))
                                    .image)
              == Approx(0.5).margin(0.1));
    }
}

namespace {

/// The bokeh of one bright point at display position `at` (units of
/// rows) on a plate 256 columns of pixel aspect 2 wide, and on the same
/// plate desqueezed: 512 square columns, the filmback twice as wide.
/// `settings(aspect)` are the shot's for the plate of that pixel aspect.
std::pair<Bokeh, Bokeh> squeezed_and_desqueezed(const std::string& dir, const Imath::V2i& at,
                                                const std::function<Settings(int)>& settings)
{
    Bokeh bokeh[2];
    for (const int aspect : { 2, 1 }) {
        ImageSpec spec = rgbaz_spec(512 / aspect, 256);
        spec.attribute("PixelAspectRatio", float(aspect));
        ImageBuf plate(spec);
        ImageBufAlgo::fill(plate, { 0.0f, 0.0f, 0.0f, 1.0f, 20.0f });
        ImageBufAlgo::fill(plate, { 100.0f, 100.0f, 100.0f, 1.0f, 20.0f },
                           ROI(at.x / aspect, at.x / aspect + 2 / aspect, at.y, at.y + 1));
        const std::string path = dir + format("/aspect{}.exr", aspect);
        REQUIRE(plate.write(path));
        bokeh[aspect - 1] = desqueezed_bokeh(
            render_ok(path, with(settings(aspect), { { "focal", "50" }, { "fstop", "1.4" },
                                                     { "sensor", std::to_string(72 / aspect) },
                                                     { "focus", "0.5" } }))
                .image,
            aspect);
    }
    return { bokeh[1], bokeh[0] };
}

}  // namespace

TEST_CASE("on an anamorphic plate, the cat's eye, tilt and diopter act as on the desqueezed one")
{
    const std::string dir = scratch_dir("desqueezed");
    struct Case {
        const char* what;
        std::function<Settings(int)> settings;
        Imath::V2i at;
    };
    const Case cases[] = {
        { "cat's eye", [](int) { return Settings { { "cateye", "1" } }; }, { 440, 40 } },
        { "tilt", [](int) { return Settings { { "focus-tilt", "0,20" } }; }, { 400, 128 } },
    };
    for (const Case& c : cases) {
        const auto [squeezed, desqueezed] = squeezed_and_desqueezed(dir, c.at, c.settings);
        INFO(c.what << ": centre " << squeezed.centre << " against " << desqueezed.centre
                    << ", spread " << squeezed.spread << " against " << desqueezed.spread);
        CHECK((squeezed.centre - desqueezed.centre).length() < 0.3);
        CHECK(squeezed.spread.x == Approx(desqueezed.spread.x).epsilon(0.08));
        CHECK(squeezed.spread.y == Approx(desqueezed.spread.y).epsilon(0.08));
    }
}

TEST_CASE("on an anamorphic plate, a diopter's focus changes over 4 px of the desqueezed image")
{
    // A vertical line through pixel centres: 4 px across on the desqueezed
    // image are 2 columns of pixel aspect 2, with 1 centre strictly inside.
    for (const double aspect : { 1.0, 2.0 }) {
        Camera camera;
        camera.focus_distance = 1.0;
        camera.split = { 100, 0, 100, 50, 2.0 };
        camera.pixel_aspect = aspect;
        const CircleOfConfusion coc(camera, ROI(0, 200, 0, 50));
        int changing = 0;
        for (int x = 90; x < 110; ++x) {
            const double f = coc.inverse_focus(x, 10);
            changing += f != coc.inverse_focus(0, 10) && f != coc.inverse_focus(199, 10);
        }
        INFO("pixel aspect " << aspect);
        CHECK(changing == int(CircleOfConfusion::split_transition_px / aspect) - 1);
    }
}

TEST_CASE("ray distance on an anamorphic plate: a column spans pixel aspect times the field")
{
    Camera squeezed, square;
    squeezed.pixel_aspect = 2.0;
    squeezed.axis_pixel = square.axis_pixel = Imath::V2d(49.0, 24.5);  // centre 49.5, 25
    const ROI display(0, 100, 0, 50);
    const PlanarDepth from_squeezed(DepthKind::Distance, squeezed, display, 1.0);
    const PlanarDepth from_square(DepthKind::Distance, square, display, 1.0);
    // Column 80's centre is 31 columns right of the centre: 62 on the
    // desqueezed image, where the square plate's column 111 is.
    CHECK(from_squeezed(10.0, 80, 7) == Approx(from_square(10.0, 111, 7)).epsilon(1e-12));
    CHECK(from_squeezed(10.0, 80, 7) < from_square(10.0, 80, 7));
}
