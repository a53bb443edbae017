// Data channels that survive defocus: cryptomatte mattes decode to each
// object's share of the output alpha, IDs and P/N are never a mix, depth is
// coverage-weighted beside the front-most layer's.
#include <catch2/catch.hpp>

#include <cstring>
#include <limits>

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>

#include <defocus/composite/data_channels.h>
#include <defocus/frame_report.h>
#include <defocus/io/image_output.h>
#include <defocus/io/shot_assets.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using namespace OIIO;

namespace {

constexpr int frame_width = 160, frame_height = 100;
constexpr uint32_t front_hash = 0x3f123456u, back_hash = 0x40abcdefu;

float hash_float(uint32_t bits)
{
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
}

const std::vector<std::string> channels = {
    "R", "G", "B", "A", "Z", "CryptoObject00.R", "CryptoObject00.G", "CryptoObject00.B",
    "CryptoObject00.A", "objectId", "P.x", "P.y", "P.z", "N.x", "N.y", "N.z"
};

/// One object's pixels: colour, depth, cryptomatte (its hash, all of the
/// pixel), ID, position and normal.
std::vector<float> object_pixel(bool front)
{
    if (front)
        return { 0.9f, 0.3f, 0.1f, 1.0f, 2.0f, hash_float(front_hash), 1.0f, 0.0f, 0.0f, 1.0f,
                 -1.0f, 0.0f, 2.0f, 0.0f, 1.0f, 0.0f };
    return { 0.2f, 0.5f, 0.8f, 1.0f, 5.0f, hash_float(back_hash), 1.0f, 0.0f, 0.0f, 2.0f,
             1.0f, 2.0f, 5.0f, 0.0f, 0.0f, 1.0f };
}

const ROI front_card(20, 70, 35, 65), back_card(40, 140, 20, 80);

ImageSpec scene_spec()
{
    ImageSpec spec(frame_width, frame_height, int(channels.size()), TypeFloat);
    spec.channelnames = channels;
    spec.alpha_channel = 3;
    spec.z_channel = 4;
    spec.attribute("cryptomatte/0a1b2c3/name", "CryptoObject");
    return spec;
}

/// A flat render of a card at 2 m partly in front of a card at 5 m (or of
/// one of them alone), with cryptomatte, an ID, P and N.
std::string flat_scene(const std::string& dir, bool with_front, bool with_back)
{
    ImageBuf image(scene_spec());
    std::vector<float> empty(channels.size(), 0.0f);
    empty[4] = 1e10f;
    ImageBufAlgo::fill(image, empty);
    if (with_back)
        ImageBufAlgo::fill(image, object_pixel(false), back_card);
    if (with_front)
        ImageBufAlgo::fill(image, object_pixel(true), front_card);
    const std::string path = Strutil::fmt::format("{}/flat{}{}.exr", dir, with_front, with_back);
    REQUIRE(image.write(path));
    return path;
}

/// The same cards as the parts of a layered EXR, the back one first; a
/// card left out leaves its part empty.
std::string layered_scene(const std::string& dir, bool with_front, bool with_back)
{
    const std::string path
        = Strutil::fmt::format("{}/layered{}{}.exr", dir, with_front, with_back);
    auto out = ImageOutput::create(path);
    ImageSpec specs[2] = { scene_spec(), scene_spec() };
    specs[0].attribute("name", "back");
    specs[1].attribute("name", "front");
    REQUIRE(out->open(path, 2, specs));
    for (int part = 0; part < 2; ++part) {
        ImageBuf image(specs[part]);
        std::vector<float> empty(channels.size(), 0.0f);
        empty[4] = 1e10f;
        ImageBufAlgo::fill(image, empty);
        if (part == 1 ? with_front : with_back)
            ImageBufAlgo::fill(image, object_pixel(part == 1), part == 1 ? front_card : back_card);
        REQUIRE((part == 0 || out->open(path, specs[part], ImageOutput::AppendSubimage)));
        REQUIRE(out->write_image(TypeFloat, image.localpixels()));
    }
    REQUIRE(out->close());
    return path;
}

/// The same cards as a deep image: a sample for each card a pixel shows,
/// the one behind kept where the other hides it.
std::string deep_scene(const std::string& dir, bool with_front, bool with_back)
{
    ImageSpec spec = scene_spec();
    spec.deep = true;
    DeepData data(spec);
    for (int y = 0; y < frame_height; ++y)
        for (int x = 0; x < frame_width; ++x) {
            std::vector<std::vector<float>> samples;
            if (with_front && front_card.contains(x, y))
                samples.push_back(object_pixel(true));
            if (with_back && back_card.contains(x, y))
                samples.push_back(object_pixel(false));
            const int64_t p = int64_t(y) * frame_width + x;
            data.set_samples(p, int(samples.size()));
            for (int k = 0; k < int(samples.size()); ++k)
                for (int c = 0; c < int(channels.size()); ++c)
                    data.set_deep_value(p, c, k, samples[k][c]);
        }
    const std::string path = Strutil::fmt::format("{}/deep{}{}.exr", dir, with_front, with_back);
    auto out = ImageOutput::create(path);
    REQUIRE(out->open(path, spec));
    REQUIRE(out->write_deep_image(data));
    REQUIRE(out->close());
    return path;
}

/// Blur of about 26 px at 2 m and 15 px at 5 m.
const Settings camera = { { "focus", "3.2" }, { "fstop", "1.4" }, { "focal", "85" },
                          { "sensor", "6" } };

Settings with_data(const std::string& value = "auto")
{
    Settings settings = camera;
    settings.emplace_back("data-channels", value);
    return settings;
}

/// The matte of the object `hash` decoded from a defocused result's
/// cryptomatte rank pairs at (x, y).
float matte(const ImageBuf& image, uint32_t hash, int x, int y)
{
    const ImageSpec& spec = image.spec();
    float sum = 0.0f;
    for (const char* rank : { "R", "B" }) {
        const std::string id = std::string("CryptoObject00.") + rank;
        const std::string coverage = std::string("CryptoObject00.") + (rank[0] == 'R' ? "G" : "A");
        const float value = image.getchannel(x, y, 0, spec.channelindex(id));
        uint32_t bits;
        std::memcpy(&bits, &value, sizeof bits);
        if (bits == hash)
            sum += image.getchannel(x, y, 0, spec.channelindex(coverage));
    }
    return sum;
}

/// Checks the issue's bars on `result`: each object's decoded matte is the
/// alpha of that object defocused alone wherever the other one, alone,
/// does not reach; everywhere, the mattes sum to the output alpha.
void check_mattes(const ImageBuf& result, const ImageBuf& front_alone, const ImageBuf& back_alone)
{
    float worst_front = 0.0f, worst_back = 0.0f, worst_sum = 0.0f;
    int front_only = 0, back_only = 0;
    for (int y = 0; y < frame_height; ++y)
        for (int x = 0; x < frame_width; ++x) {
            const float front = matte(result, front_hash, x, y);
            const float back = matte(result, back_hash, x, y);
            const float front_alpha = front_alone.getchannel(x, y, 0, 3);
            const float back_alpha = back_alone.getchannel(x, y, 0, 3);
            if (back_alpha < 1e-4f) {
                worst_front = std::max(worst_front, std::abs(front - front_alpha));
                front_only += front_alpha > 0.01f;
            }
            if (front_alpha < 1e-4f) {
                worst_back = std::max(worst_back, std::abs(back - back_alpha));
                back_only += back_alpha > 0.01f;
            }
            worst_sum = std::max(worst_sum, std::abs(front + back - result.getchannel(x, y, 0, 3)));
        }
    CHECK(front_only > 300);  // the test covers the blurred edges of both
    CHECK(back_only > 3000);
    CHECK(worst_front < 1e-3f);
    CHECK(worst_back < 1e-3f);
    CHECK(worst_sum < 1e-3f);
}

}  // namespace

TEST_CASE("decoded cryptomatte mattes are each object's share of the defocused alpha")
{
    const std::string dir = scratch_dir("data_crypto");
    SECTION("a flat render")
    {
        check_mattes(rendered(flat_scene(dir, true, true), with_data()),
                     rendered(flat_scene(dir, true, false), camera),
                     rendered(flat_scene(dir, false, true), camera));
    }
    SECTION("a layered EXR, one card a part")
    {
        check_mattes(rendered(layered_scene(dir, true, true), with_data()),
                     rendered(layered_scene(dir, true, false), camera),
                     rendered(layered_scene(dir, false, true), camera));
    }
    SECTION("a deep image")
    {
        check_mattes(rendered(deep_scene(dir, true, true), with_data()),
                     rendered(deep_scene(dir, true, false), camera),
                     rendered(deep_scene(dir, false, true), camera));
    }
    SECTION("written as half, the IDs stay float and the mattes still sum to the alpha")
    {
        const std::string out = dir + "/half.exr";
        Settings settings = with_data();
        settings.emplace_back("pixel-type", "half");
        FrameResult result;
        std::string error;
        REQUIRE(render_with(flat_scene(dir, true, true), settings, result, error));
        REQUIRE(write_image_atomic(result.image, out, result.pixel_type, "", error,
                                   result.data_channels));
        const ImageSpec spec = read_spec(out);
        CHECK(spec.channelformat(spec.channelindex("A")) == TypeHalf);
        CHECK(spec.channelformat(spec.channelindex("CryptoObject00.R")) == TypeFloat);
        const ImageBuf written = read_image(out);
        CHECK(matte(written, back_hash, 120, 50) == Approx(1.0f).margin(1e-3));
        CHECK(matte(written, front_hash, 45, 50) == Approx(1.0f).margin(1e-3));
    }
}

TEST_CASE("IDs, P and N after defocus are one contributor's, never a mix")
{
    const std::string dir = scratch_dir("data_dominant");
    // Through aperture cells too, which composite the cards per part of the
    // lens where the front one cuts into the back one's blur.
    Settings settings = with_data();
    settings.emplace_back("aperture-cells", GENERATE(as<std::string>(), "1", "0"));
    INFO("--aperture-cells " << settings.back().second);
    const ImageBuf out = rendered(flat_scene(dir, true, true), settings);
    const ImageSpec& spec = out.spec();
    const int id = spec.channelindex("objectId");
    REQUIRE(id >= 0);
    int mixed_alpha = 0;
    for (int y = 0; y < frame_height; ++y)
        for (int x = 0; x < frame_width; ++x) {
            const float value = out.getchannel(x, y, 0, id);
            INFO(x << "," << y);
            REQUIRE((value == 0.0f || value == 1.0f || value == 2.0f));
            float p[3], n[3];
            for (int c = 0; c < 3; ++c) {
                p[c] = out.getchannel(x, y, 0, spec.channelindex(std::string("P.") + "xyz"[c]));
                n[c] = out.getchannel(x, y, 0, spec.channelindex(std::string("N.") + "xyz"[c]));
            }
            // A value spread and divided by its spread alpha: equal within
            // float rounding.
            auto is = [&](float x, float y, float z) {
                return std::abs(p[0] - x) < 1e-4f && std::abs(p[1] - y) < 1e-4f
                       && std::abs(p[2] - z) < 1e-4f;
            };
            const bool front = is(-1.0f, 0.0f, 2.0f), back = is(1.0f, 2.0f, 5.0f);
            const bool none = p[0] == 0.0f && p[1] == 0.0f && p[2] == 0.0f;
            REQUIRE((front || back || none));
            const float length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            REQUIRE((none ? length == 0.0f : std::abs(length - 1.0f) < 1e-5f));
            // The ID and the surface belong to the same object.
            if (front || back)
                REQUIRE(value == (front ? 1.0f : 2.0f));
            const float a = out.getchannel(x, y, 0, 3);
            mixed_alpha += a > 0.2f && a < 0.8f;
        }
    CHECK(mixed_alpha > 500);  // blurred edges, where averaging would mix
    CHECK(out.getchannel(45, 50, 0, id) == 1.0f);
    CHECK(out.getchannel(120, 50, 0, id) == 2.0f);
}

TEST_CASE("Z is the coverage-weighted depth, ZFront the front-most layer's")
{
    const std::string dir = scratch_dir("data_depth");
    const ImageBuf out = rendered(flat_scene(dir, true, true), with_data());
    const int z = out.spec().channelindex("Z"), front = out.spec().channelindex("ZFront");
    REQUIRE(z >= 0);
    REQUIRE(front >= 0);
    int edges = 0;
    for (int y = 0; y < frame_height; ++y)
        for (int x = 0; x < frame_width; ++x) {
            const float a = matte(out, front_hash, x, y), b = matte(out, back_hash, x, y);
            if (a + b < 0.01f)
                continue;
            INFO(x << "," << y);
            REQUIRE(out.getchannel(x, y, 0, z) == Approx((2.0f * a + 5.0f * b) / (a + b)).margin(2e-3));
            if (a > 0.01f && b > 0.01f) {
                ++edges;
                REQUIRE(out.getchannel(x, y, 0, front) == Approx(2.0f).margin(1e-4));
            }
        }
    CHECK(edges > 500);
    CHECK(out.getchannel(2, 2, 0, z) == 0.0f);  // nothing there
}

TEST_CASE("data channels leave the colour as it is, and only what is asked is carried")
{
    const std::string dir = scratch_dir("data_select");
    const std::string scene = flat_scene(dir, true, true);
    const ImageBuf plain = rendered(scene, camera);
    REQUIRE(plain.nchannels() == 4);
    const ImageBuf named = rendered(scene, with_data("objectId:id,P.x:average"));
    REQUIRE(named.nchannels() == 6);
    CHECK(named.spec().channelnames[4] == "objectId");
    CHECK(named.spec().channelnames[5] == "P.x");
    CHECK(ImageBufAlgo::compare(ImageBufAlgo::channels(named, 4, {}), plain, 0.0f, 0.0f).maxerror
          == 0.0);
    // Averaged P.x where both cards reach: between theirs, not either.
    CHECK(named.getchannel(70, 50, 0, 5) > -1.0f);
    CHECK(named.getchannel(70, 50, 0, 5) < 1.0f);
    // Left out, they are named for -v, with the setting that carries them.
    auto noted = [&](const Settings& settings) {
        FrameResult result;
        std::string error;
        REQUIRE(render_with(scene, settings, result, error));
        const std::string all = command_line_words(Strutil::join(result.notes, "\n"));
        return Strutil::contains(all, "data channels left out: objectId, N, P, CryptoObject "
                                      "(--data-channels auto carries them)");
    };
    CHECK(noted(camera));
    CHECK_FALSE(noted(with_data("Z")));
    // -v says what is carried, and as what.
    FrameResult result;
    std::string error;
    const Settings carried = with_data("objectId:id,P.x:average");
    REQUIRE(render_with(scene, carried, result, error));
    CHECK_THAT(frame_report(result, shot_with({ scene }, carried), "out.exr"),
               Catch::Contains("  data channels carried: objectId (id), P.x (average)\n"));
    const ImageBuf depth_only = rendered(scene, with_data("Z"));
    CHECK(depth_only.spec().channelnames == std::vector<std::string>({ "R", "G", "B", "A", "Z", "ZFront" }));
}

TEST_CASE("a data channels setting that cannot be carried is refused in one line")
{
    const std::string dir = scratch_dir("data_refused");
    const std::string scene = flat_scene(dir, true, true);
    FrameResult result;
    std::string error;
    CHECK_FALSE(render_with(scene, with_data("auto,matId"), result, error));
    CHECK(one_line_error(error, "--data-channels auto,matId: the input has no channel matId"));
    CHECK(one_line_error(error, scene));
    Settings deep = with_data();
    deep.emplace_back("deep", "on");
    CHECK_FALSE(render_with(scene, deep, result, error));
    CHECK(one_line_error(error, "--data-channels cannot be written with --deep"));
    Settings map = with_data();
    map.emplace_back("output", "focusmap");
    CHECK_FALSE(render_with(scene, map, result, error));
    CHECK(one_line_error(error, "--data-channels applies to the defocused image"));
}

TEST_CASE("a continuous channel declared an ID is refused before its values are spread")
{
    // Every pixel its own value: thousands of "objects" over the frame.
    const std::string dir = scratch_dir("data_continuous");
    ImageSpec spec(frame_width, frame_height, 6, TypeFloat);
    spec.channelnames = { "R", "G", "B", "A", "Z", "noise" };
    spec.alpha_channel = 3;
    spec.z_channel = 4;
    ImageBuf image(spec);
    for (int y = 0; y < frame_height; ++y)
        for (int x = 0; x < frame_width; ++x) {
            const float pixel[6] = { 0.5f, 0.5f, 0.5f, 1.0f, 5.0f,
                                     float((x * 7919 + y * 104729) % 10007) / 10007.0f };
            image.setpixel(x, y, pixel);
        }
    const std::string scene = dir + "/noise.exr";
    REQUIRE(image.write(scene));
    FrameResult result;
    std::string error;
    CHECK_FALSE(render_with(scene, with_data("noise:id"), result, error));
    CHECK(one_line_error(error, "noise: 10007 distinct values strewn over the frame, as a "
                                "continuous channel has"));
    CHECK_THAT(command_line_words(error), Catch::EndsWith("carry it with --data-channels "
                                                          "noise:average"));
    // As what it is, it is carried.
    REQUIRE(render_with(scene, with_data("noise:average"), result, error));
}

TEST_CASE("the data channels' spreads say how far they are, and stop when cancelled")
{
    // Python's Ctrl-C came 14 s late: the stage asked only as it began; and
    // thousands of IDs ran for minutes without a word.
    const std::string dir = scratch_dir("data_cancelled");
    const Shot shot = shot_with({ flat_scene(dir, true, true) }, with_data());
    ShotAssets assets;
    std::string error;
    REQUIRE(read_shot_assets(shot, assets, error));
    std::vector<std::string> said;
    auto data_stage = [&](const char* stage) {
        if (stage && Strutil::starts_with(stage, "data channels"))
            said.push_back(stage);
    };
    FrameResult result;
    // Each spread says so, counting up to all of them.
    REQUIRE(render_frame(shot, 1, assets, result, error, [&](const char* stage) {
        data_stage(stage);
        return true;
    }));
    REQUIRE(said.size() >= 2);
    for (size_t k = 0; k < said.size(); ++k)
        CHECK(said[k] == Strutil::fmt::format("data channels {}/{}", k, said.size()));
    // Cancelled as the second spread asks: it stops there.
    said.clear();
    CHECK_FALSE(render_frame(shot, 1, assets, result, error, [&](const char* stage) {
        data_stage(stage);
        return said.size() < 2;
    }));
    CHECK_THAT(error, Catch::EndsWith(": cancelled"));
    CHECK(said.size() == 2);
}

TEST_CASE("an object that is all of its layer's light is matted by the layer's own spread")
{
    // A part per object, as a layered render is often written: each
    // object's matte is its part's alpha, already spread once. It needs no
    // spread of its own (the layered section above checks that the mattes
    // are still each card's alpha); two objects at one depth share a layer
    // and need theirs.
    const std::string dir = scratch_dir("data_whole_objects");
    auto spreads = [&](const std::string& scene) {
        // One spread for the layers' alphas (and no quantities), then the
        // IDs' mattes.
        const Shot shot = shot_with({ scene }, with_data("objectId:id"));
        ShotAssets assets;
        std::string error;
        REQUIRE(read_shot_assets(shot, assets, error));
        int said = 0;
        FrameResult result;
        REQUIRE(render_frame(shot, 1, assets, result, error, [&](const char* stage) {
            said += stage && Strutil::starts_with(stage, "data channels");
            return true;
        }));
        return said;
    };
    CHECK(spreads(layered_scene(dir, true, true)) == 1);
    ImageBuf one_depth(scene_spec());
    std::vector<float> empty(channels.size(), 0.0f), front = object_pixel(true);
    empty[4] = 1e10f;
    front[4] = object_pixel(false)[4];
    ImageBufAlgo::fill(one_depth, empty);
    ImageBufAlgo::fill(one_depth, object_pixel(false), back_card);
    ImageBufAlgo::fill(one_depth, front, front_card);
    REQUIRE(one_depth.write(dir + "/one_depth.exr"));
    CHECK(spreads(dir + "/one_depth.exr") == 2);
}

TEST_CASE("bad data values never reach the output, and integer IDs come out whole")
{
    const std::string dir = scratch_dir("data_bad");
    ImageBuf image(scene_spec());
    std::vector<float> empty(channels.size(), 0.0f);
    empty[4] = 1e10f;
    ImageBufAlgo::fill(image, empty);
    ImageBufAlgo::fill(image, object_pixel(false), back_card);
    ImageBufAlgo::fill(image, object_pixel(true), front_card);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    std::vector<float> sky(channels.size(), 0.0f);  // opaque, infinitely far
    sky[2] = sky[3] = 1.0f;
    sky[4] = inf;
    ImageBufAlgo::fill(image, sky, ROI(0, frame_width, 0, 6));
    const int id = 9, coverage = 6, px = 10;
    for (int y = 40; y < 60; ++y) {
        image.setpixel(50, y, std::vector<float> { 0.9f, 0.3f, 0.1f, 1.0f, 2.0f, nan, nan, 0.0f,
                                                   0.0f, inf, nan, 1e38f, -inf, nan, 0.0f,
                                                   1.0f }.data());
    }
    REQUIRE(image.getchannel(50, 45, 0, coverage) != image.getchannel(50, 45, 0, coverage));
    REQUIRE(std::isinf(image.getchannel(50, 45, 0, id)));
    REQUIRE(std::isnan(image.getchannel(50, 45, 0, px)));
    const std::string bad = dir + "/bad.exr";
    REQUIRE(image.write(bad));
    const ImageBuf out = rendered(bad, with_data());
    CHECK(no_nan(out));
    CHECK(out.getchannel(80, 0, 0, out.spec().channelindex("Z")) > 1e29f);  // the sky, far

    // IDs stored as unsigned integers, as some renderers write them.
    ImageSpec spec = scene_spec();
    spec.channelformats.assign(channels.size(), TypeFloat);
    spec.channelformats[id] = TypeUInt;
    const std::string integer = dir + "/integer.exr";
    auto file = ImageOutput::create(integer);
    ImageBuf source(scene_spec());
    ImageBufAlgo::fill(source, empty);
    ImageBufAlgo::fill(source, object_pixel(false), back_card);
    ImageBufAlgo::fill(source, object_pixel(true), front_card);
    // Native pixels: the ID as an unsigned integer, not a scaled float.
    std::vector<uint32_t> native(size_t(frame_width) * frame_height * channels.size());
    const float* from = static_cast<const float*>(source.localpixels());
    for (size_t i = 0; i < native.size(); ++i) {
        if (i % channels.size() == size_t(id))
            native[i] = uint32_t(from[i]);
        else
            std::memcpy(&native[i], &from[i], sizeof(float));
    }
    REQUIRE(file->open(integer, spec));
    REQUIRE(file->write_image(TypeUnknown, native.data()));
    REQUIRE(file->close());
    const ImageSpec written = read_spec(integer);
    REQUIRE(written.channelformat(written.channelindex("objectId")) == TypeUInt);
    const ImageBuf ids = rendered(integer, with_data("objectId:id"));
    CHECK(ids.getchannel(45, 50, 0, 4) == 1.0f);
    CHECK(ids.getchannel(120, 50, 0, 4) == 2.0f);
}

TEST_CASE("data channels are found by their names, Blender's view-layer prefix and all")
{
    ImageSpec spec(8, 8, 0, TypeFloat);
    for (const char* name :
         { "ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B",
           "ViewLayer.Combined.A", "ViewLayer.Depth.Z", "ViewLayer.IndexOB", "ViewLayer.Normal.X",
           "ViewLayer.Normal.Y", "ViewLayer.Normal.Z", "ViewLayer.CryptoObject00.R",
           "ViewLayer.CryptoObject00.G", "ViewLayer.CryptoObject00.B",
           "ViewLayer.CryptoObject00.A", "ViewLayer.CryptoObject01.R", "diffuse.R" })
        spec.channelnames.push_back(name);
    spec.nchannels = int(spec.channelnames.size());
    DataPlan plan;
    std::string error;
    REQUIRE(plan_data_channels(spec, "auto", plan, error));
    CHECK(plan.depth);
    REQUIRE(plan.crypto.size() == 1);
    CHECK(plan.crypto[0].name == "ViewLayer.CryptoObject");
    CHECK(plan.crypto[0].ranks() == 2);  // the incomplete second quad is left out
    REQUIRE(plan.channels.size() == 4);
    CHECK(plan.channels[0].name == "ViewLayer.IndexOB");
    CHECK(plan.channels[0].kind == DataKind::Id);
    for (int c = 1; c < 4; ++c) {
        CHECK(plan.channels[c].kind == DataKind::Dominant);
        CHECK(plan.channels[c].normal);
    }
    // Named: a kind changed, another channel added, none.
    REQUIRE(plan_data_channels(spec, "auto,ViewLayer.IndexOB:average,diffuse.R:id", plan, error));
    CHECK(plan.channels[0].kind == DataKind::Average);
    CHECK(plan.channels.back().name == "diffuse.R");
    CHECK(plan.channels.back().kind == DataKind::Id);
    REQUIRE(plan_data_channels(spec, "none", plan, error));
    CHECK(plan.empty());
}
