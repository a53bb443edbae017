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

#include <defocus/frame_report.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using namespace OIIO;

namespace {

constexpr int width = 200, height = 100;

/// A striped wall at 5 m from column `left` on, nothing left of it (by
/// default, over the right half).
std::string wall(const std::string& dir, int left = width / 2)
{
    ImageBuf image(rgbaz_spec(width, height));
    ImageBufAlgo::fill(image, { 0.0f, 0.0f, 0.0f, 0.0f, 1e9f });
    for (int x = left; x < width; x += 20)
        ImageBufAlgo::fill(image, { 1.0f, 0.8f, 0.6f, 1.0f, 5.0f }, ROI(x, x + 10, 0, height));
    for (int x = left + 10; x < width; x += 20)
        ImageBufAlgo::fill(image, { 0.1f, 0.2f, 0.3f, 1.0f, 5.0f }, ROI(x, x + 10, 0, height));
    const std::string path = dir + "/wall" + std::to_string(left) + ".exr";
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
    // -v names the holdout.
    FrameResult result;
    std::string error;
    REQUIRE(render_with(scene, behind, result, error));
    CHECK_THAT(frame_report(result, shot_with({ scene }, behind), "out.exr"),
               Catch::Contains("  holdout: " + behind.back().second + " ("));
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

namespace {

/// Whether every pixel's samples of a deep result run front to back
/// without overlapping (Z <= ZBack <= the next Z), with finite values and
/// alpha within [0, 1].
bool sorted_and_disjoint(const ImageBuf& deep)
{
    const DeepData& data = *deep.deepdata();
    const int z = deep.spec().channelindex("Z"), zback = deep.spec().channelindex("ZBack");
    for (int64_t p = 0; p < data.pixels(); ++p) {
        float back = 0.0f;
        for (int s = 0; s < data.samples(p); ++s) {
            for (int c = 0; c < data.channels(); ++c)
                if (!std::isfinite(data.deep_value(p, c, s)))
                    return false;
            const float a = data.deep_value(p, 3, s);
            if (a < 0.0f || a > 1.0f || data.deep_value(p, z, s) < back
                || data.deep_value(p, zback, s) < data.deep_value(p, z, s))
                return false;
            back = data.deep_value(p, zback, s);
        }
    }
    return true;
}

/// The samples of `deep` that add less than 1e-6 to every channel of their
/// pixel through the samples in front of them: the spreads' faint tails,
/// and whatever lies behind an opaque sample.
int64_t empty_samples(const ImageBuf& deep)
{
    const DeepData& data = *deep.deepdata();
    int64_t empty = 0;
    for (int64_t p = 0; p < data.pixels(); ++p) {
        float through = 1.0f;
        for (int s = 0; s < data.samples(p); ++s) {
            float largest = 0.0f;
            for (int c = 0; c < 4; ++c)
                largest = std::max(largest, std::abs(data.deep_value(p, c, s)));
            empty += through * largest < 1e-6f;
            through *= 1.0f - std::clamp(data.deep_value(p, 3, s), 0.0f, 1.0f);
        }
    }
    return empty;
}

/// The RGBA of a deep result flattened.
ImageBuf flattened(const ImageBuf& deep)
{
    return ImageBufAlgo::channels(ImageBufAlgo::flatten(deep), 4, {});
}

}  // namespace

TEST_CASE("a deep result's samples are sorted and disjoint, and flatten to the flat result")
{
    // A bar at 1 m and a half-transparent square at 2 m in front of a
    // striped wall at 5 m, focus at 3 m: three depth layers, each blurred.
    const std::string dir = scratch_dir("deep_output");
    ImageBuf image(rgbaz_spec(width, height));
    ImageBufAlgo::fill(image, { 0.2f, 0.3f, 0.4f, 1.0f, 5.0f });
    for (int x = 0; x < width; x += 20)
        ImageBufAlgo::fill(image, { 2.0f, 1.6f, 1.2f, 1.0f, 5.0f }, ROI(x, x + 10, 0, height));
    ImageBufAlgo::fill(image, { 0.5f, 0.1f, 0.1f, 0.5f, 2.0f }, ROI(120, 170, 20, 70));
    ImageBufAlgo::fill(image, { 0.9f, 0.9f, 0.9f, 1.0f, 1.0f }, ROI(60, 80, 0, height));
    const std::string scene = dir + "/bars.exr";
    REQUIRE(image.write(scene));
    const Settings camera = { { "focal", "50" }, { "fstop", "1" }, { "focus", "3" },
                              { "pixel-type", "float" } };
    const std::vector<Settings> variants = {
        {}, { { "window", "grown" } }, { { "aperture", "polygon" }, { "blades", "6" } },
        { { "cateye", "0.5" } }, { { "layers", "2" } },
        // Converted linearly, sample by sample, as the flat result is.
        { { "tocolorspace", "ACES2065-1" } },
    };
    for (const Settings& variant : variants) {
        Settings flat = camera;
        flat.insert(flat.end(), variant.begin(), variant.end());
        INFO(flat.back().first << " " << flat.back().second);
        Settings deep = flat;
        deep.push_back({ "deep", "on" });
        const ImageBuf out = rendered(scene, deep);
        REQUIRE(out.deep());
        CHECK(out.spec().channelnames
              == std::vector<std::string> { "R", "G", "B", "A", "Z", "ZBack" });
        CHECK(sorted_and_disjoint(out));
        CHECK(empty_samples(out) == 0);
        const ImageBuf expected = rendered(scene, flat);
        ROI window = out.roi();
        window.chend = 4;
        CHECK(window == expected.roi());
        CHECK(largest_difference(flattened(out), expected) < 1e-5f);
    }
}

TEST_CASE("merged deep results of two elements are the two elements defocused together")
{
    // A deep card at 2 m over the left half and a striped wall at 5 m
    // behind all of it, each defocused alone into a deep result, then
    // merged: the same as the two merged first (nothing culled) and
    // defocused as one deep input, whose layers are the same two.
    const std::string dir = scratch_dir("deep_merge");
    ImageBuf wall_flat(wall(dir, 0));
    REQUIRE(wall_flat.read());
    // With ZBack, as the card has it.
    const ImageBuf wall_rgbazz = ImageBufAlgo::channels(
        wall_flat, 6, { 0, 1, 2, 3, 4, 4 }, {}, { "R", "G", "B", "A", "Z", "ZBack" });
    ImageBuf wall_deep;
    REQUIRE(ImageBufAlgo::deepen(wall_deep, wall_rgbazz));
    const std::string wall_file = dir + "/wall_deep.exr";
    REQUIRE(wall_deep.write(wall_file));
    const std::string card_file = card(dir, 2.0f, 1.0f);
    ImageBuf card_deep(card_file);
    REQUIRE(card_deep.read());
    ImageBuf both;
    REQUIRE(ImageBufAlgo::deep_merge(both, card_deep, wall_deep, false));
    const std::string both_file = dir + "/both.exr";
    REQUIRE(both.write(both_file));

    // Focus between them: the card's CoC is -18.5 px, the wall's 14, so
    // that the deep input is cut into the same two layers. (Focused
    // beyond both, their CoCs differ by less than a layer holds, and one
    // layer would spread them together.) Composited per cell of the
    // aperture, an element alone cannot know what the other hides from
    // each part of the lens; compositing the whole aperture at once, the
    // merge is exact.
    const Settings camera = { { "focal", "100" }, { "fstop", "0.5" }, { "focus", "3" },
                              { "pixel-type", "float" }, { "window", "display" },
                              { "aperture-cells", "1" } };
    Settings deep = camera;
    deep.push_back({ "deep", "on" });
    const ImageBuf card_out = rendered(card_file, deep), wall_out = rendered(wall_file, deep);
    ImageBuf merged;
    REQUIRE(ImageBufAlgo::deep_merge(merged, card_out, wall_out));
    CHECK(sorted_and_disjoint(merged));
    const ImageBuf together = rendered(both_file, camera);
    // The card's blur reaches over the wall, and the wall's behind the card.
    CHECK(largest_difference(flattened(merged), together) < 1e-5f);
    CHECK(largest_difference(flattened(card_out), together) > 0.1f);
}
