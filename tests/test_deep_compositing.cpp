// Deep compositing: holdouts (the shot's other elements, as a deep image,
// cut the defocused element where they stand in front of it, per output
// pixel), and the CoC AOV.
#include <catch2/catch.hpp>

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <defocus/composite/holdout.h>
#include <defocus/io/frames.h>
#include <defocus/optics/camera.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using namespace OIIO;

namespace {

constexpr int width = 200, height = 100;

/// A striped wall at 5 m over the right half, nothing on the left.
std::string wall(const std::string& dir)
{
    ImageBuf image(rgbaz_spec(width, height));
    ImageBufAlgo::fill(image, { 0.0f, 0.0f, 0.0f, 0.0f, 1e9f });
    for (int x = width / 2; x < width; x += 20)
        ImageBufAlgo::fill(image, { 1.0f, 0.8f, 0.6f, 1.0f, 5.0f }, ROI(x, x + 10, 0, height));
    for (int x = width / 2 + 10; x < width; x += 20)
        ImageBufAlgo::fill(image, { 0.1f, 0.2f, 0.3f, 1.0f, 5.0f }, ROI(x, x + 10, 0, height));
    const std::string path = dir + "/wall.exr";
    REQUIRE(image.write(path));
    return path;
}

/// A deep card at `depth` over the left half, of alpha `alpha`: one sample
/// a pixel there, none on the right.
std::string card(const std::string& dir, float depth, float alpha)
{
    ImageSpec spec(width, height, 6, TypeFloat);
    spec.channelnames = { "R", "G", "B", "A", "Z", "ZBack" };
    spec.deep = true;
    DeepData data(spec);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width / 2; ++x) {
            const int64_t p = int64_t(y) * width + x;
            data.set_samples(p, 1);
            const float values[6] = { 0.3f * alpha, 0.3f * alpha, 0.3f * alpha, alpha, depth,
                                      depth };
            for (int c = 0; c < 6; ++c)
                data.set_deep_value(p, c, 0, values[c]);
        }
    const std::string path = dir + "/card_" + std::to_string(depth) + "_"
                             + std::to_string(alpha) + ".exr";
    auto out = ImageOutput::create(path);
    REQUIRE(out->open(path, spec));
    REQUIRE(out->write_deep_image(data));
    REQUIRE(out->close());
    return path;
}

/// The largest difference between `a` scaled by `scale` and `b` over the
/// columns [x0, x1).
float worst(const ImageBuf& a, float scale, const ImageBuf& b, int x0, int x1)
{
    float most = 0.0f;
    for (int y = 0; y < height; ++y)
        for (int x = x0; x < x1; ++x)
            for (int c = 0; c < 4; ++c)
                most = std::max(most, std::abs(scale * a.getchannel(x, y, 0, c)
                                               - b.getchannel(x, y, 0, c)));
    return most;
}

}  // namespace

TEST_CASE("a deep card in front holds out the blurred wall behind it, its spread blur too")
{
    const std::string dir = scratch_dir("holdout_card");
    const std::string scene = wall(dir);
    // The wall at 5 m blurs to a CoC of about 60 px across: a radius of 30.
    const Settings camera = { { "focal", "50" }, { "fstop", "0.417" }, { "focus", "0.5" },
                              { "edge", "black" } };
    const ImageBuf plain = rendered(scene, camera);
    const int radius = 31;
    // The blur spreads the wall's light over the card's half.
    CHECK(worst(plain, 0.0f, plain, width / 2 - radius + 5, width / 2) > 0.05f);

    for (const float alpha : { 1.0f, 0.5f }) {
        INFO("alpha " << alpha);
        Settings held = camera;
        held.push_back({ "holdout", card(dir, 2.0f, alpha) });
        const ImageBuf out = rendered(scene, held);
        // Behind the card, what reaches the output is cut by its alpha:
        // nothing of an opaque card, half of a half-transparent one.
        CHECK(worst(plain, 1.0f - alpha, out, 0, width / 2) < 1e-4f);
        // More than the blur's radius from it, nothing changes.
        CHECK(worst(plain, 1.0f, out, width / 2 + radius, width) == 0.0f);
    }
    // A card behind the wall cuts nothing of it.
    Settings behind = camera;
    behind.push_back({ "holdout", card(dir, 8.0f, 1.0f) });
    CHECK(worst(plain, 1.0f, rendered(scene, behind), 0, width) == 0.0f);
}

TEST_CASE("a holdout sequence is one of the shot's: a missing frame of it is missing, or held")
{
    const std::string dir = scratch_dir("holdout_sequence");
    const std::string scene = wall(dir);
    REQUIRE(Filesystem::copy(card(dir, 2.0f, 1.0f), dir + "/card.0001.exr"));
    const Settings settings = { { "focal", "50" }, { "fstop", "0.417" }, { "focus", "0.5" },
                                { "frames", "1-2" }, { "holdout", dir + "/card.#.exr" } };
    Shot shot = shot_with({ scene }, settings);
    std::vector<int> frames;
    std::string error;
    CHECK_FALSE(shot_frames(shot, frames, error));
    CHECK_THAT(error, Catch::Contains("card.0002.exr: no such file"));
    // Held: frame 2 is cut by frame 1's holdout.
    Settings held = settings;
    held.push_back({ "missing-frames", "hold" });
    REQUIRE(shot_frames(shot_with({ scene }, held), frames, error));
    CHECK(frames == std::vector<int> { 1, 2 });
    const ImageBuf first = rendered(scene, held, 1), second = rendered(scene, held, 2);
    CHECK(ImageBufAlgo::compare(first, second, 0.0f, 0.0f).maxerror == 0.0);
    CHECK(worst(first, 0.0f, first, 0, width / 2) == 0.0f);  // cut: nothing behind the card
}

TEST_CASE("a holdout's volume samples are cut where the depth range splits them")
{
    DeepImage holdout;
    holdout.roi = ROI(0, 1, 0, 1);
    holdout.offsets = { 0, 2 };
    // A point sample at 1 m, alpha 0.5; a volume from 2 to 4 m, alpha 0.75.
    holdout.samples = { { 0, 0, 0, 0.5f, 1.0f, 1.0f }, { 0, 0, 0, 0.75f, 2.0f, 4.0f } };
    CHECK(holdout_transmittance(holdout, 0, 0, 0.0, 1.0) == 1.0);  // up to, not at, 1 m
    CHECK(holdout_transmittance(holdout, 0, 0, 0.0, 1.5) == 0.5);
    // Half of the volume passes sqrt(0.25) of the light; both halves, 0.25.
    CHECK(holdout_transmittance(holdout, 0, 0, 1.5, 3.0) == Approx(0.5));
    CHECK(holdout_transmittance(holdout, 0, 0, 3.0, 10.0) == Approx(0.5));
    CHECK(holdout_transmittance(holdout, 0, 0, 0.0, 10.0) == Approx(0.5 * 0.25));
    CHECK(holdout_transmittance(holdout, 5, 5, 0.0, 10.0) == 1.0);  // outside its window
}

TEST_CASE("the CoC AOV is the signed CoC of the front-most layer that reaches each pixel")
{
    // A bar at 1 m in front of a wall at 10 m, focus at 3 m.
    const std::string dir = scratch_dir("coc_aov");
    ImageBuf image(rgbaz_spec(120, 60));
    ImageBufAlgo::fill(image, { 0.2f, 0.3f, 0.4f, 1.0f, 10.0f });
    ImageBufAlgo::fill(image, { 0.9f, 0.9f, 0.9f, 1.0f, 1.0f }, ROI(50, 70, 0, 60));
    const std::string scene = dir + "/bar.exr";
    REQUIRE(image.write(scene));
    const Settings settings = { { "focal", "50" }, { "fstop", "0.5" }, { "focus", "3" },
                                { "aov", "coc" } };
    const ImageBuf out = rendered(scene, settings);
    REQUIRE(out.nchannels() == 5);
    CHECK(out.spec().channelnames[4] == "coc");

    Camera camera;
    camera.focal_length_mm = 50;
    camera.fstop = 0.5;
    camera.focus_distance = 3;
    const CircleOfConfusion coc(camera, ROI(0, 120, 0, 60));
    const double near = coc.diameter(1.0, 0, 0), far = coc.diameter(10.0, 0, 0);
    REQUIRE(near < -10.0);  // a radius of more than 5 px
    REQUIRE(far > 2.0);
    auto aov = [&](int x) { return out.getchannel(x, 30, 0, 4); };
    CHECK(aov(60) == Approx(near).epsilon(1e-4));
    CHECK(aov(10) == Approx(far).epsilon(1e-4));   // the bar's blur is far away
    CHECK(aov(110) == Approx(far).epsilon(1e-4));
    // Beside the bar, where its blur reaches over the wall: the bar's.
    CHECK(aov(48) == Approx(near).epsilon(1e-4));
    CHECK(aov(71) == Approx(near).epsilon(1e-4));
    // The colour is the same as without the AOV.
    Settings plain = settings;
    plain.pop_back();
    const ImageBuf colour = rendered(scene, plain);
    CHECK(ImageBufAlgo::compare(ImageBufAlgo::channels(out, 4, {}), colour, 0.0f, 0.0f).maxerror
          == 0.0);
}
