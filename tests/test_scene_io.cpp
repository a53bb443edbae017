// Reading every kind of layered scene a pipeline produces, from small files
// written here.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include <defocus/io/file_stamps.h>
#include <defocus/io/frames.h>
#include <defocus/io/image_output.h>
#include <defocus/io/scene_io.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using namespace OIIO;

namespace {

/// One part of a test file: channel names, a constant value per channel,
/// and optionally a view and a name.
struct PartDesc {
    std::vector<std::string> channels;
    std::vector<float> values;
    std::string view, name;
};

std::string write_parts(const std::string& file, const std::vector<PartDesc>& parts)
{
    const std::string path = scratch_dir("scene_io_" + file) + "/" + file;
    std::vector<ImageSpec> specs;
    for (const PartDesc& p : parts) {
        ImageSpec spec(8, 6, int(p.channels.size()), TypeFloat);
        spec.channelnames = p.channels;
        if (!p.view.empty())
            spec.attribute("view", p.view);
        spec.attribute("name", p.name.empty() ? Strutil::fmt::format("part{}", specs.size())
                                              : p.name);
        specs.push_back(spec);
    }
    auto out = ImageOutput::create(path);
    REQUIRE(out->open(path, int(specs.size()), specs.data()));
    for (size_t i = 0; i < parts.size(); ++i) {
        if (i > 0)
            REQUIRE(out->open(path, specs[i], ImageOutput::AppendSubimage));
        ImageBuf buf(specs[i]);
        ImageBufAlgo::fill(buf, parts[i].values);
        REQUIRE(out->write_image(TypeFloat, buf.localpixels()));
    }
    REQUIRE(out->close());
    return path;
}

/// A deep file (deepscanline, or deeptile with `tiled`): every pixel
/// holds `samples` R,G,B,A,Z samples (R,G,B,Z without `alpha`).
std::string write_deep(const std::string& file, const std::vector<std::array<float, 5>>& samples,
                       bool tiled = false, bool alpha = true)
{
    const std::string path = scratch_dir("scene_io_" + file) + "/" + file;
    const std::vector<int> source = alpha ? std::vector<int> { 0, 1, 2, 3, 4 }
                                          : std::vector<int> { 0, 1, 2, 4 };
    ImageSpec spec(4, 3, int(source.size()), TypeFloat);
    spec.channelnames = alpha ? std::vector<std::string> { "R", "G", "B", "A", "Z" }
                              : std::vector<std::string> { "R", "G", "B", "Z" };
    spec.deep = true;
    if (tiled)
        spec.tile_width = spec.tile_height = 16;
    DeepData data(spec);
    for (int64_t p = 0; p < data.pixels(); ++p) {
        data.set_samples(p, int(samples.size()));
        for (int s = 0; s < int(samples.size()); ++s)
            for (int c = 0; c < int(source.size()); ++c)
                data.set_deep_value(p, c, s, samples[s][source[c]]);
    }
    auto out = ImageOutput::create(path);
    REQUIRE(out->open(path, spec));
    REQUIRE(out->write_deep_image(data));
    REQUIRE(out->close());
    return path;
}

Scene read(const std::vector<std::string>& files, const ReadOptions& options = {})
{
    Scene scene;
    std::string error;
    INFO(error);
    REQUIRE(read_scene(files, options, scene, error));
    return scene;
}

std::string read_error(const std::vector<std::string>& files, const ReadOptions& options = {})
{
    Scene scene;
    std::string error;
    CHECK_FALSE(read_scene(files, options, scene, error));
    return command_line_words(error);
}

float value(const ImageBuf& image, int channel)
{
    float p[4];
    image.getpixel(2, 2, p);
    return p[channel];
}

}  // namespace

TEST_CASE("every piece of a scene's content is visited: layers, flat renders, deep images")
{
    Scene scene;
    scene.layers.push_back(Layer { "given", ImageBuf(), ImageBuf() });
    scene.flat.push_back(Layer { "render", ImageBuf(), ImageBuf() });
    DeepImage deep;
    deep.name = "deep";
    scene.deep.push_back(deep);
    std::vector<std::string> seen;
    const Scene& as_read = scene;
    CHECK(for_each_content(as_read,
        [&](const Layer& layer) { seen.push_back(layer.name); return true; },
        [&](const DeepImage& image) { seen.push_back(image.name); return true; }));
    CHECK(seen == std::vector<std::string> { "given", "render", "deep" });
    // A visit that fails stops there.
    seen.clear();
    CHECK_FALSE(for_each_content(scene,
        [&](Layer& layer) { seen.push_back(layer.name); return layer.name != "render"; },
        [&](DeepImage& image) { seen.push_back(image.name); return true; }));
    CHECK(seen == std::vector<std::string> { "given", "render" });
}

TEST_CASE("a single RGBA+Z image is a flat render")
{
    const std::string f = write_parts("flat.exr", { { { "R", "G", "B", "A", "Z" }, { 1, 2, 3, 1, 5 } } });
    const Scene s = read({ f });
    REQUIRE(s.flat.size() == 1);
    CHECK(s.layers.empty());
    CHECK(value(s.flat[0].depth, 0) == 5.0f);
}

TEST_CASE("every compression reads back exactly, zip chunks (inflated by libdeflate) too")
{
    // Values that vary from pixel to pixel, as a render's do, in float and
    // in half, scanline and tiled, over more than one chunk.
    ImageSpec spec(67, 45, 5, TypeFloat);
    spec.channelnames = { "R", "G", "B", "A", "Z" };
    ImageBuf source(spec);
    for (int y = 0; y < spec.height; ++y)
        for (int x = 0; x < spec.width; ++x) {
            const float v[5] = { std::sin(0.37f * x + 0.11f * y) * 40.0f, 0.001f * x * y,
                                 float(x ^ y), 1.0f, 1.0f + 0.25f * float((x * 7 + y * 13) % 31) };
            source.setpixel(x, y, v);
        }
    for (const TypeDesc type : { TypeDesc(TypeFloat), TypeDesc(TypeHalf) })
        for (const char* compression : { "none", "zip", "zips", "piz", "rle" })
            for (const bool tiled : { false, true }) {
                INFO(type << " " << compression << (tiled ? " tiled" : ""));
                ImageSpec file_spec = spec;
                file_spec.set_format(type);
                file_spec.attribute("compression", compression);
                if (tiled)
                    file_spec.tile_width = file_spec.tile_height = 16;
                const std::string path = scratch_dir("scene_io_compression") + "/c.exr";
                auto out = ImageOutput::create(path);
                REQUIRE(out->open(path, file_spec));
                REQUIRE(out->write_image(TypeFloat, source.localpixels()));
                REQUIRE(out->close());
                // What the file holds, rounded to its pixel type.
                ImageBuf expected;
                REQUIRE(ImageBufAlgo::copy(expected, source, type));
                const Scene s = read({ path });
                REQUIRE(s.flat.size() == 1);
                const Layer& flat = s.flat[0];
                double worst = 0.0;
                for (int y = 0; y < spec.height; ++y)
                    for (int x = 0; x < spec.width; ++x) {
                        float want[5], color[4], depth = 0.0f;
                        expected.getpixel(x, y, want);
                        flat.color.getpixel(x, y, color);
                        flat.depth.getpixel(x, y, &depth, 1);
                        for (int c = 0; c < 4; ++c)
                            worst = std::max(worst, double(std::abs(color[c] - want[c])));
                        worst = std::max(worst, double(std::abs(depth - want[4])));
                    }
                CHECK(worst == 0.0);
            }
}

TEST_CASE("parts that each hold RGBA+Z are the layers")
{
    const std::string f = write_parts("layers.exr", { { { "R", "G", "B", "A", "Z" }, { 1, 0, 0, 1, 9 }, "", "back" },
                                                      { { "R", "G", "B", "A", "Z" }, { 0, 1, 0, 1, 2 }, "", "front" } });
    const Scene s = read({ f });
    REQUIRE(s.layers.size() == 2);
    CHECK(s.layers[1].name == "front");
    CHECK(value(s.layers[1].depth, 0) == 2.0f);
}

TEST_CASE("Blender multilayer channel names are understood")
{
    const std::string f = write_parts("blender.exr", { { { "ViewLayer.Combined.R", "ViewLayer.Combined.G",
                                                           "ViewLayer.Combined.B", "ViewLayer.Combined.A",
                                                           "ViewLayer.Depth.Z" },
                                                         { 0.5f, 0.25f, 0.125f, 1, 7 } } });
    const Scene s = read({ f });
    REQUIRE(s.flat.size() == 1);
    CHECK(value(s.flat[0].color, 1) == 0.25f);
    CHECK(value(s.flat[0].depth, 0) == 7.0f);
    ReadOptions by_name;
    by_name.layer = "ViewLayer";
    CHECK(value(read({ f }, by_name).flat[0].depth, 0) == 7.0f);
}

TEST_CASE("a chosen layer name picks among prefixed channel sets")
{
    const std::string f = write_parts("prefixed.exr", { { { "beauty.R", "beauty.G", "beauty.B", "beauty.A", "beauty.Z",
                                                            "spec.R", "spec.G", "spec.B", "spec.A" },
                                                          { 1, 1, 1, 1, 3, 2, 2, 2, 1 } } });
    CHECK_THAT(read_error({ f }), Catch::Contains("--layer"));
    ReadOptions beauty;
    beauty.layer = "beauty";
    const Scene s = read({ f }, beauty);
    REQUIRE(s.flat.size() == 1);
    CHECK(value(s.flat[0].depth, 0) == 3.0f);
}

TEST_CASE("a beauty part and a depth part of the same view are joined")
{
    const std::string f = write_parts("joined.exr", { { { "R", "G", "B", "A" }, { 1, 1, 1, 1 } },
                                                      { { "depth.Z" }, { 4 } } });
    const Scene s = read({ f });
    REQUIRE(s.flat.size() == 1);
    CHECK(value(s.flat[0].depth, 0) == 4.0f);
}

TEST_CASE("a chosen view picks that view's parts of a stereo file")
{
    const std::string f = write_parts("stereo.exr", { { { "R", "G", "B", "A" }, { 1, 0, 0, 1 }, "right" },
                                                      { { "Z" }, { 2 }, "left" },
                                                      { { "R", "G", "B", "A" }, { 0, 1, 0, 1 }, "left" },
                                                      { { "Z" }, { 3 }, "right" } });
    const Scene first = read({ f });  // the first part's view: right
    REQUIRE(first.flat.size() == 1);
    CHECK(value(first.flat[0].color, 0) == 1.0f);
    CHECK(value(first.flat[0].depth, 0) == 3.0f);
    ReadOptions left;
    left.view = "left";
    const Scene l = read({ f }, left);
    CHECK(value(l.flat[0].color, 1) == 1.0f);
    CHECK(value(l.flat[0].depth, 0) == 2.0f);
    ReadOptions centre;
    centre.view = "centre";
    CHECK_THAT(read_error({ f }, centre), Catch::Contains("views: right, left"));
}

TEST_CASE("several files are the layers of one scene")
{
    const std::string a = write_parts("bg.exr", { { { "R", "G", "B", "A", "Z" }, { 1, 0, 0, 1, 9 } } });
    const std::string b = write_parts("fg.exr", { { { "R", "G", "B", "A", "Z" }, { 0, 1, 0, 1, 2 } } });
    const Scene s = read({ a, b });
    CHECK(s.flat.empty());
    CHECK(s.layers.size() == 2);
}

TEST_CASE("deep scanline and tiled files are read, and several are merged pixel by pixel")
{
    const std::string a = write_deep("a.exr", { { 0.1f, 0.2f, 0.3f, 0.5f, 4.0f } });
    const std::string b = write_deep("b.exr", { { 0.5f, 0.5f, 0.5f, 1.0f, 9.0f },
                                                { 0.2f, 0.0f, 0.0f, 0.2f, 1.0f } });
    const Scene one = read({ a });
    REQUIRE(one.deep.size() == 1);
    CHECK(one.deep[0].samples.size() == 12);
    CHECK(one.deep[0].samples[5].z == 4.0f);
    const std::string t = write_deep("tiled.exr", { { 0.1f, 0.2f, 0.3f, 0.5f, 4.0f } }, true);
    CHECK(read_spec(t).tile_width == 16);
    CHECK(read({ t }).deep[0].samples[5].z == 4.0f);
    const Scene both = read({ a, b });
    REQUIRE(both.deep.size() == 1);
    CHECK(both.deep[0].offsets[1] == 3);  // 1 + 2 samples in the first pixel
    CHECK(both.deep[0].samples.size() == 36);
}

TEST_CASE("a deep image is written sample for sample, whatever room its pixels hold")
{
    // 37 rows: bands of rows and a short last one. Pixel p holds p % 3
    // samples; every seventh has room for two more than it holds, so
    // that its samples do not follow the previous pixel's.
    ImageSpec spec(11, 37, 6, TypeFloat);
    spec.channelnames = { "R", "G", "B", "A", "Z", "ZBack" };
    spec.channelformats = { TypeHalf, TypeHalf, TypeHalf, TypeHalf, TypeFloat, TypeFloat };
    spec.alpha_channel = 3;
    spec.z_channel = 4;
    spec.deep = true;
    for (const bool room : { false, true }) {
        ImageBuf image(spec);
        DeepData& deep = *image.deepdata();
        for (int64_t p = 0; p < deep.pixels(); ++p) {
            deep.set_samples(p, int(p % 3));
            if (room && p % 7 == 0)
                deep.set_capacity(p, int(p % 3) + 2);
        }
        auto value = [](int64_t p, int c, int s) {
            return float((p * 8 + c * 2 + s) % 1024) / 4.0f;  // exact in half
        };
        for (int64_t p = 0; p < deep.pixels(); ++p)
            for (int s = 0; s < deep.samples(p); ++s)
                for (int c = 0; c < 6; ++c)
                    deep.set_deep_value(p, c, s, value(p, c, s));
        const std::string file = scratch_dir("deep_write") + (room ? "/room.exr" : "/tight.exr");
        std::string error;
        REQUIRE(write_image_atomic(image, file, TypeUnknown, "none", error));
        ImageBuf back(file);
        REQUIRE(back.read(0, 0, true));
        const DeepData& read = *back.deepdata();
        REQUIRE(read.pixels() == deep.pixels());
        int64_t wrong = 0;
        for (int64_t p = 0; p < deep.pixels(); ++p) {
            wrong += read.samples(p) != deep.samples(p);
            for (int s = 0; s < std::min(read.samples(p), deep.samples(p)); ++s)
                for (int c = 0; c < 6; ++c)
                    wrong += read.deep_value(p, c, s) != value(p, c, s);
        }
        INFO((room ? "with room" : "tight"));
        CHECK(wrong == 0);
    }
}

TEST_CASE("inputs with different display windows are refused")
{
    const std::string a = write_parts("a.exr", { { { "R", "G", "B", "A", "Z" }, { 1, 0, 0, 1, 9 } } });
    const std::string path = scratch_dir("scene_io_wide") + "/wide.exr";
    ImageSpec spec(16, 6, 5, TypeFloat);
    spec.channelnames = { "R", "G", "B", "A", "Z" };
    ImageBuf wide(spec);
    ImageBufAlgo::fill(wide, { 1, 1, 1, 1, 1 });
    REQUIRE(wide.write(path));
    CHECK_THAT(read_error({ a, path }), Catch::Contains("display window"));
}

TEST_CASE("colour without alpha is read as opaque, and said so")
{
    const std::string f = write_parts("rgbz.exr", { { { "R", "G", "B", "Z" }, { 0.5f, 0.25f, 0, 3 } } });
    const Scene s = read({ f });
    REQUIRE(s.flat.size() == 1);
    CHECK(value(s.flat[0].color, 0) == 0.5f);
    CHECK(value(s.flat[0].color, 3) == 1.0f);
    REQUIRE(s.notes.size() == 1);
    CHECK_THAT(s.notes[0], Catch::Contains("rgbz.exr") && Catch::Contains("opaque"));
    // A set with alpha is the beauty; one without is a colour pass.
    const std::string passes = write_parts("passes.exr", { { { "beauty.R", "beauty.G", "beauty.B",
                                                               "beauty.A", "beauty.Z", "diffuse.R",
                                                               "diffuse.G", "diffuse.B" },
                                                             { 1, 1, 1, 0.5f, 3, 2, 2, 2 } } });
    const Scene beauty = read({ passes });
    CHECK(value(beauty.flat[0].color, 3) == 0.5f);
    CHECK(beauty.notes.empty());
    // Deep samples without alpha have no coverage to composite by.
    const std::string deep = write_deep("deep_rgb.exr", { { 1, 1, 1, 1, 3 } }, false, false);
    CHECK_THAT(read_error({ deep }), Catch::Contains("deep_rgb.exr") && Catch::Contains("no A channel"));
}

TEST_CASE("a depth channel named by the user, or a depth file, stands in for Z")
{
    const std::string f = write_parts("rgba.exr", { { { "R", "G", "B", "A", "P.z" }, { 1, 1, 1, 1, 6 } } });
    CHECK_THAT(read_error({ f }), Catch::Contains("no Z channel") && Catch::Contains("--depth"));
    ReadOptions by_channel;
    by_channel.depth = "P.z";
    CHECK(value(read({ f }, by_channel).flat[0].depth, 0) == 6.0f);

    // A one-channel depth file over a smaller data window: depth it does
    // not cover is 0, which sanitize() takes as missing.
    const std::string depth = scratch_dir("scene_io_depth_file") + "/depth.exr";
    ImageSpec spec(8, 6, 1, TypeFloat);
    spec.width        = 5;
    spec.channelnames = { "Y" };
    ImageBuf plane(spec);
    ImageBufAlgo::fill(plane, { 2.5f });
    REQUIRE(plane.write(depth));
    ReadOptions by_file;
    by_file.depth = depth;
    const Scene s = read({ f }, by_file);
    REQUIRE(s.flat.size() == 1);
    CHECK(value(s.flat[0].depth, 0) == 2.5f);
    float z = -1;
    s.flat[0].depth.getpixel(7, 2, &z, 1);
    CHECK(z == 0.0f);
    CHECK(std::find(s.notes.begin(), s.notes.end(), "depth from " + depth) != s.notes.end());

    ReadOptions missing;
    missing.depth = "nothing";
    CHECK_THAT(read_error({ f }, missing),
               Catch::Contains("--depth nothing") && Catch::Contains("no such file"));
    ReadOptions several;
    several.depth = f;  // R,G,B,A,P.z: which one is the depth?
    CHECK_THAT(read_error({ f }, several), Catch::Contains("no Z channel"));
    CHECK_THAT(read_error({ f, f }, by_file), Catch::Contains("not 2 inputs"));
    const std::string wide = scratch_dir("scene_io_depth_wide") + "/wide.exr";
    ImageBuf wide_plane(ImageSpec(9, 6, 1, TypeFloat));
    REQUIRE(wide_plane.write(wide));
    ReadOptions other_window;
    other_window.depth = wide;
    CHECK_THAT(read_error({ f }, other_window), Catch::Contains("display window"));
}

TEST_CASE("a numbered name of a file that exists names its frame, and no other name does")
{
    const std::string dir = scratch_dir("numbered_file");
    REQUIRE(Filesystem::write_text_file(dir + "/shot.dof", "{}"));
    std::string file;
    int frame = 0;
    CHECK(numbered_file(dir + "/shot.1001.dof", file, frame));
    CHECK(file == dir + "/shot.dof");
    CHECK(frame == 1001);
    CHECK(numbered_file(dir + "/shot.-5.dof", file, frame));
    CHECK(frame == -5);
    CHECK_FALSE(numbered_file(dir + "/shot.dof", file, frame));  // exists: no frame
    CHECK_FALSE(numbered_file(dir + "/shot.10x.dof", file, frame));
    CHECK_FALSE(numbered_file(dir + "/shot.1234567890.dof", file, frame));
    CHECK_FALSE(numbered_file(dir + "/other.1001.dof", file, frame));
}

TEST_CASE("a file rewritten, replaced or made since it was stamped is the first changed")
{
    const std::string dir = scratch_dir("file_stamps");
    const std::string a = dir + "/a.txt", b = dir + "/b.txt";
    REQUIRE(Filesystem::write_text_file(a, "one"));
    Filesystem::remove(b);
    std::vector<FileStamp> stamps = stamp_files({ a, b });
    CHECK(first_changed(stamps) == "");
    REQUIRE(Filesystem::write_text_file(b, "new"));
    CHECK(first_changed(stamps) == b);
    stamps = stamp_files({ a, b });
    REQUIRE(Filesystem::write_text_file(a, "three"));
    CHECK(first_changed(stamps) == a);
    stamps = stamp_files({ a, b });
    REQUIRE(Filesystem::write_text_file(dir + "/c.txt", "other"));
    REQUIRE(Filesystem::rename(dir + "/c.txt", a));
    CHECK(first_changed(stamps) == a);
}
