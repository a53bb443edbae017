// Cutting flat and deep content into depth layers.
#include <catch2/catch.hpp>

#include <cmath>

#include <OpenImageIO/imagebufalgo.h>

#include <defocus/composite/defocus_layers.h>
#include <defocus/layers/layering.h>
#include <defocus/layers/mixed_pixels.h>
#include <defocus/render_frame.h>
#include <defocus/shot/shot.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using OIIO::ImageBuf;
using OIIO::ROI;

namespace {

/// A flat render of size width x height (120x80 unless given) from a
/// colour and a depth per pixel.
template<typename Shade>
Scene flat_scene(Shade&& shade, int width = 120, int height = 80)
{
    Scene scene;
    scene.spec = OIIO::ImageSpec(width, height, 4, OIIO::TypeFloat);
    const ROI frame(0, width, 0, height);
    Layer flat { "flat", zero_image(frame, 4), zero_image(frame, 1) };
    flat.color.specmod().alpha_channel = 3;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            float rgba[4], z;
            shade(x, y, rgba, z);
            flat.color.setpixel(x, y, rgba);
            flat.depth.setpixel(x, y, &z);
        }
    scene.flat.push_back(std::move(flat));
    return scene;
}

/// A 120x80 scene of one deep pixel at (x, y) holding `samples`.
Scene deep_pixel(const std::string& name, int x, int y, std::vector<DeepSample> samples)
{
    Scene scene;
    scene.spec = OIIO::ImageSpec(120, 80, 4, OIIO::TypeFloat);
    DeepImage deep;
    deep.name = name;
    deep.roi = ROI(x, x + 1, y, y + 1);
    deep.offsets = { 0, samples.size() };
    deep.samples = std::move(samples);
    scene.deep.push_back(std::move(deep));
    return scene;
}

/// A scene cut into layers through `camera`, its CoC over a 120 px frame.
struct Cut {
    LayeredScene layers;
    Slicing slicing;
};
Cut cut(Scene scene, const Camera& camera, const LayeringOptions& options = {})
{
    Cut out;
    std::string error;
    REQUIRE(decompose_layers(std::move(scene), CircleOfConfusion(camera, ROI(0, 120, 0, 120)),
                             options, out.layers, out.slicing, error));
    return out;
}

ImageBuf render(Scene scene, double focus, const LayeringOptions& options = {})
{
    const Camera camera = synthetic_camera(focus);
    const LayeredScene layers = cut(std::move(scene), camera, options).layers;
    ImageBuf out;
    REQUIRE(defocus_layers(out, layers, camera));
    return out;
}

/// Composites the layers' pixel (x, y) front to back.
void composite_pixel(const std::vector<Layer>& layers, int x, int y, float out[4])
{
    std::fill(out, out + 4, 0.0f);
    // Nearest first: layering orders them back to front.
    for (auto layer = layers.rbegin(); layer != layers.rend(); ++layer) {
        float p[4];
        layer->color.getpixel(x, y, p);
        const float t = 1.0f - out[3];
        for (int c = 0; c < 4; ++c)
            out[c] += t * p[c];
    }
}

}  // namespace

TEST_CASE("a split pixel composites back to itself exactly")
{
    for (float a : { 0.1f, 0.5f, 0.99f, 1.0f })
        for (float w : { 0.0f, 0.1f, 0.5f, 0.9f, 1.0f }) {
            const SplitWeights s = split_weights(w, a);
            const float front = s.front * a, back = s.back * a;
            INFO("alpha " << a << " front weight " << w);
            CHECK(front + (1.0f - front) * back == Approx(a).epsilon(1e-6));
        }
}

TEST_CASE("membership blends continuously across a boundary, hard elsewhere")
{
    const LayerBounds bounds({ -30.0, -10.0, 10.0, 30.0 }, 2.0);
    CHECK(bounds.count() == 3);
    auto front_share = [&](double c) {
        const LayerBounds::Share s = bounds.share(c);
        return s.front + (1.0 - s.front_weight);  // a continuous layer coordinate
    };
    CHECK(bounds.share(0.0).front == 1);
    CHECK(bounds.share(0.0).front_weight == 1.0f);
    CHECK(bounds.share(-20.0).front == 0);
    double previous = front_share(-12.0);
    for (double c = -12.0; c <= -8.0; c += 0.05) {
        const double now = front_share(c);
        CHECK(now >= previous - 1e-6);
        CHECK(now - previous < 0.05);
        previous = now;
    }
    CHECK(front_share(-10.0) == Approx(0.5));
}

TEST_CASE("automatic boundaries fall in the gaps between objects")
{
    // Two planes: CoC -30 px (depth 0.526) on the left, +20 px (depth 2.5)
    // on the right, with focus at 1: nothing in between.
    Scene scene = flat_scene([](int x, int, float* rgba, float& z) {
        rgba[0] = rgba[1] = rgba[2] = 0.5f;
        rgba[3] = 1.0f;
        z = x < 60 ? 1.0f / (1.0f + 30.0f / 33.333f) : 1.0f / (1.0f - 20.0f / 33.333f);
    });
    const CircleOfConfusion coc(synthetic_camera(1.0), ROI(0, 120, 0, 120));
    LayeringOptions options;
    const LayerBounds bounds = choose_layer_bounds(scene, coc, options);
    REQUIRE(bounds.count() >= 2);
    bool boundary_in_gap = false;
    for (int k = 1; k < bounds.count(); ++k)
        boundary_in_gap |= bounds.boundary(k) > -29.0 && bounds.boundary(k) < 19.0;
    CHECK(boundary_in_gap);
    for (int k = 0; k < bounds.count(); ++k)
        CHECK(bounds.boundary(k + 1) - bounds.boundary(k) <= options.max_coc_span + 0.5);
    // --layers N spaces N layers evenly instead.
    options.layers = 5;
    const LayerBounds even = choose_layer_bounds(scene, coc, options);
    CHECK(even.count() == 5);
    CHECK(even.boundary(1) - even.boundary(0) == Approx(even.boundary(5) - even.boundary(4)));
}

TEST_CASE("a deep volume sample split across layers composites back to itself")
{
    // A fog volume from 0.6 to 6 (CoC -22 to +28 px) behind a point sample.
    LayeringOptions options;
    options.layers = 6;
    const auto [layers, slicing] = cut(deep_pixel("volume", 10, 10,
                                                  { { 0.4f, 0.2f, 0.1f, 0.8f, 0.6f, 6.0f },
                                                    { 0.1f, 0.1f, 0.1f, 0.2f, 0.55f, 0.55f } }),
                                       synthetic_camera(1.0), options);
    REQUIRE(layers.layers.size() >= 3);
    // Back to front, each layer with its own report.
    REQUIRE(layers.reports.size() == layers.layers.size());
    for (size_t i = 0; i < layers.layers.size(); ++i) {
        CHECK(layers.reports[i].name == layers.layers[i].name);
        if (i > 0)
            CHECK(layers.reports[i - 1].mean_inverse_depth < layers.reports[i].mean_inverse_depth);
    }
    float out[4];
    composite_pixel(layers.layers, 10, 10, out);
    // Point sample (a = 0.2) over the volume (a = 0.8), in that order.
    const float expected[4] = { 0.1f + 0.8f * 0.4f, 0.1f + 0.8f * 0.2f,
                                0.1f + 0.8f * 0.1f, 0.2f + 0.8f * 0.8f };
    for (int c = 0; c < 4; ++c)
        CHECK(out[c] == Approx(expected[c]).epsilon(1e-5));
}

TEST_CASE("deep samples are ordered by Z, then ZBack")
{
    // File order: the longer volume first. At equal Z the shorter one
    // (smaller ZBack) is in front.
    const LayeredScene layers
        = cut(deep_pixel("tie", 0, 0,
                         { { 0.0f, 0.5f, 0.0f, 0.5f, 2.0f, 4.0f },    // green, long
                           { 0.5f, 0.0f, 0.0f, 0.5f, 2.0f, 2.0f } }),  // red, point
              synthetic_camera(1.0))
              .layers;
    float out[4];
    composite_pixel(layers.layers, 0, 0, out);
    CHECK(out[0] == Approx(0.5f));   // red in front
    CHECK(out[1] == Approx(0.25f));  // green behind it
}

TEST_CASE("a sample behind an opaque one adds nothing to its layer's depth")
{
    // 0 times the infinite depth of the sky behind an opaque sample made
    // the layer's depth NaN (fuzz_scene), which put the layers out of
    // order and gave aperture cells a NaN radius.
    const LayeredScene layers
        = cut(deep_pixel("wall", 0, 0,
                         { { 0.5f, 0.5f, 0.5f, 1.0f, 1000.0f, 1000.0f },
                           { 0.2f, 0.3f, 0.9f, 1.0f, INFINITY, INFINITY } }),
              synthetic_camera(1.0))
              .layers;
    int lit = 0;
    for (const Layer& layer : layers.layers) {
        if (!(layer.color.getchannel(0, 0, 0, 3) > 0.0f))
            continue;
        ++lit;
        CHECK(layer.depth.getchannel(0, 0, 0, 0) == 1000.0f);
    }
    CHECK(lit == 1);
}

TEST_CASE("a surface crossing layer boundaries shows no seam")
{
    // An opaque grey plane tilted in depth: its CoC runs from -20 to +20 px
    // across the frame, through the boundaries of 5 layers.
    Scene scene = flat_scene([](int x, int, float* rgba, float& z) {
        rgba[0] = rgba[1] = rgba[2] = 0.5f;
        rgba[3] = 1.0f;
        const double c = -20.0 + 40.0 * x / 119.0;
        z = float(1.0 / (1.0 - c / 33.333));
    });
    LayeringOptions options;
    options.layers = 5;
    const ImageBuf out = render(scene, 1.0, options);
    double worst = 0.0;
    for (int y = 30; y < 50; ++y)
        for (int x = 20; x < 100; ++x) {
            float p[4];
            out.getpixel(x, y, p);
            worst = std::max({ worst, std::abs(p[3] - 1.0), std::abs(p[0] / 0.5 - 1.0) });
        }
    // A hard cut with nothing behind it leaves a 25% dip along each seam.
    CHECK(worst < 0.01);
}

TEST_CASE("the hidden background of a flat render is filled behind nearer layers")
{
    // A flat render of a card in front of a plain wall: the wall behind the
    // card is missing. With the card blurred, the result must match the
    // complete two-layer scene, where the wall behind the card exists.
    const ROI card(40, 80, 20, 60);
    auto shade = [&](int x, int y, float* rgba, float& z) {
        const bool in_card = card.contains(x, y);
        rgba[0] = in_card ? 0.9f : 0.2f;
        rgba[1] = in_card ? 0.1f : 0.4f;
        rgba[2] = 0.3f;
        rgba[3] = 1.0f;
        z = in_card ? 1.0f : 10.0f;
    };
    const ImageBuf flat_result = render(flat_scene(shade), 10.0);

    Scene complete = flat_scene([](int, int, float* rgba, float& z) {
        rgba[0] = 0.2f, rgba[1] = 0.4f, rgba[2] = 0.3f, rgba[3] = 1.0f;
        z = 10.0f;
    });
    complete.layers.push_back(std::move(complete.flat.front()));
    complete.flat.clear();
    Layer front { "card", zero_image(card, 4), zero_image(card, 1) };
    OIIO::ImageBufAlgo::fill(front.color, { 0.9f, 0.1f, 0.3f, 1.0f });
    OIIO::ImageBufAlgo::fill(front.depth, { 1.0f });
    front.color.specmod().alpha_channel = 3;
    complete.layers.push_back(std::move(front));
    const ImageBuf truth = render(std::move(complete), 10.0);

    double worst = 0.0;
    for (int y = 0; y < 80; ++y)
        for (int x = 0; x < 120; ++x) {
            float a[4], b[4];
            flat_result.getpixel(x, y, a);
            truth.getpixel(x, y, b);
            for (int c = 0; c < 4; ++c)
                worst = std::max(worst, double(std::abs(a[c] - b[c])));
        }
    // Without the fill, the card's see-through edge shows black: ~0.2 off.
    CHECK(worst < 0.01);
}

TEST_CASE("an in-focus light's antialiased rim grows no bokeh at the depth behind it")
{
    // A renderer writes one depth per pixel: the rim of a small light 50
    // times brighter than the wall behind it holds the light's colour but
    // the wall's depth. Spread whole with the wall's 40 px blur, the rim
    // grew a bright disc the lens does not make.
    const float light_z = 0.5f, wall_z = 1.25f;  // CoC 0, and 33.3·(2 - 0.8) = 40 px
    const float cx = 60.0f, cy = 40.0f, radius = 5.0f;
    auto coverage = [&](int x, int y) {
        int inside = 0;
        for (int sy = 0; sy < 4; ++sy)
            for (int sx = 0; sx < 4; ++sx)
                inside += std::hypot(x + (sx + 0.5f) / 4 - cx, y + (sy + 0.5f) / 4 - cy) < radius;
        return float(inside) / 16.0f;
    };
    auto shade = [&](int x, int y, float* rgba, float& z) {
        const float cover = coverage(x, y);
        std::fill(rgba, rgba + 3, cover * 50.0f + (1.0f - cover));
        rgba[3] = 1.0f;
        z = cover == 1.0f ? light_z : wall_z;
    };
    const ImageBuf out = render(flat_scene(shade), light_z);
    const ImageBuf wall = render(flat_scene([&](int, int, float* rgba, float& z) {
                                     std::fill(rgba, rgba + 4, 1.0f);
                                     z = wall_z;
                                 }),
                                 light_z);
    int ghost = 0;
    for (int y = 0; y < 80; ++y)
        for (int x = 0; x < 120; ++x)
            if (std::hypot(x + 0.5f - cx, y + 0.5f - cy) > radius + 3.0f)
                ghost += out.getchannel(x, y, 0, 1) > 1.05f * wall.getchannel(x, y, 0, 1);
    CHECK(ghost == 0);

    // Split in two, every rim pixel still composites back to itself.
    const LayeredScene layers = layered_scene(flat_scene(shade), synthetic_camera(light_z));
    for (int y = 30; y < 50; ++y)
        for (int x = 50; x < 70; ++x) {
            float rgba[4], z, composited[4];
            shade(x, y, rgba, z);
            composite_pixel(layers.layers, x, y, composited);
            for (int c = 0; c < 4; ++c)
                CHECK(composited[c] == Approx(rgba[c]).epsilon(1e-4));
        }
}

TEST_CASE("automatic layering separates every visible depth step, however narrow the blur range")
{
    // Blurs of -8, 0 and +8 px: the whole range fits in one span of 24 px,
    // so CoC bins alone made one layer, in which the blurred bar's edges
    // stay hard and the wall's blur smears over the square's sharp edges.
    const double focus = 0.5;
    const float near_z = 1.0f / 2.24f, square_z = 0.5f, wall_z = 1.0f / 1.76f;
    const CircleOfConfusion coc(synthetic_camera(focus), ROI(0, 120, 0, 80));
    const Scene steps = flat_scene([&](int x, int y, float* rgba, float& z) {
        std::fill(rgba, rgba + 4, 1.0f);
        // A vertical bar over a square over a wall.
        z = x >= 66 && x < 74 ? near_z : x >= 50 && x < 90 && y >= 20 && y < 60 ? square_z : wall_z;
    });
    const LayerBounds bounds = choose_layer_bounds(steps, coc, {});
    std::vector<int> layer_of;
    for (float z : { near_z, square_z, wall_z }) {
        const LayerBounds::Share share = bounds.share(coc.diameter(z, 60, 40));
        CHECK(share.front_weight == 1.0f);  // wholly in one layer
        layer_of.push_back(share.front);
    }
    CHECK(layer_of[0] < layer_of[1]);
    CHECK(layer_of[1] < layer_of[2]);

    // A floor seen at a grazing angle spans the same blurs with no step:
    // one layer is enough.
    const Scene floor = flat_scene([&](int, int y, float* rgba, float& z) {
        std::fill(rgba, rgba + 4, 1.0f);
        z = 1.0f / (2.24f - 0.48f * y / 79.0f);
    });
    CHECK(choose_layer_bounds(floor, coc, {}).count() == 1);
}

TEST_CASE("pixels of a textured background beside an edge are not taken for mixed ones")
{
    // Dark and light stripes beside a grey pole, with no antialiasing: the
    // stripes' mean lies near the pole's grey, and a two-colour fit took
    // every stripe pixel at the edge for a blend of the two. No pixel is
    // split; the pole's edge pixels stay whole, with the stripes continued
    // behind them as they are beside them.
    const float pole_z = 1.0f / 2.9f, stripes_z = 0.5f;
    auto stripe = [](int y) { return (y / 4) % 2 ? 1.0f : 0.1f; };
    const Scene scene = flat_scene([&](int x, int y, float* rgba, float& z) {
        const bool in_pole = x >= 55 && x < 65;
        std::fill(rgba, rgba + 3, in_pole ? 0.5f : stripe(y));
        rgba[3] = 1.0f;
        z = in_pole ? pole_z : stripes_z;
    });
    const CircleOfConfusion coc(synthetic_camera(0.5), ROI(0, 120, 0, 80));
    const std::vector<MixedPixel> mixed = find_mixed_pixels(scene.flat.front(), coc);
    CHECK(mixed.size() == 2 * 80);
    for (const MixedPixel& m : mixed) {
        INFO("pixel " << m.x << "," << m.y);
        CHECK((m.x == 55 || m.x == 64));
        CHECK(m.near[0] == 0.5f);
        CHECK(m.near[3] == 1.0f);
        CHECK(m.near_z == pole_z);
        CHECK(m.far[0] == stripe(m.y));
        CHECK(m.far[3] == 1.0f);
        CHECK(m.far_z == stripes_z);
    }
}

TEST_CASE("the confidence AOV is the share of light from rebuilt surfaces, and 0 where all was seen")
{
    // In-focus stripes behind a pole blurred to 30 px: the stripes the
    // pole hides are rebuilt, along lines across it, and show through its
    // blurred edges. Behind a pole 2 px wide nothing is filled: the
    // stripes are continued behind its edge pixels, which is as made up.
    const int width = GENERATE(10, 2);
    const float pole_z = 1.0f / 2.9f, stripes_z = 0.5f;
    auto shade = [&](int x, int y, float* rgba, float& z) {
        const bool in_pole = x >= 60 - width / 2 && x < 60 + width / 2;
        std::fill(rgba, rgba + 3, in_pole ? 0.5f : (y / 4) % 2 ? 1.0f : 0.1f);
        rgba[3] = 1.0f;
        z = in_pole ? pole_z : stripes_z;
    };
    Shot shot;
    shot.inputs = { "stripes.exr" };
    std::string error;
    for (const auto& [name, value] : { std::pair { "focal", "100" }, { "fstop", "1" },
                                       { "sensor", "36" }, { "focus", "0.5" },
                                       { "aov", "confidence" }, { "camera-from-file", "off" } })
        REQUIRE(set_shot_setting(shot, name, value, error));
    auto confidence = [&](Scene scene) {
        FrameResult result;
        std::string error;
        REQUIRE(render_scene(std::move(scene), shot, 0, {}, result, error));
        REQUIRE(result.image.nchannels() == 9);
        CHECK(std::vector<std::string>(result.image.spec().channelnames.begin() + 4,
                                       result.image.spec().channelnames.end())
              == std::vector<std::string> { "confidence", "confidence.continued",
                                            "confidence.lines", "confidence.patterns",
                                            "confidence.smooth" });
        return result.image;
    };

    const ImageBuf flat = confidence(flat_scene(shade));
    INFO("pole " << width << " px wide: confidence " << flat.getchannel(60, 40, 0, 4));
    auto at = [&](const ImageBuf& image, int x, int y, int c = 4) {
        return image.getchannel(x, y, 0, c);
    };
    // Behind the pole the light is the rebuilt stripes' as much as the
    // pole's; beyond the blur's reach all of it was seen.
    CHECK(at(flat, 60, 40) > 0.2f);
    CHECK(at(flat, 60, 40) < 0.8f);
    for (int y = 0; y < 80; y += 7)
        for (int x : { 0, 10, 30, 90, 110, 119 })
            CHECK(at(flat, x, y) == 0.0f);
    // The shares by method add up to it; behind the wide pole the stripes
    // came from the fill's structure (lines and patterns), behind the thin
    // one from its edges.
    for (int y = 0; y < 80; y += 7)
        for (int x = 0; x < 120; x += 3) {
            float sum = 0.0f;
            for (int c = 5; c < 9; ++c) {
                CHECK(at(flat, x, y, c) >= 0.0f);
                sum += at(flat, x, y, c);
            }
            CHECK(sum == Approx(at(flat, x, y)).margin(1e-5));
        }
    const float continued = at(flat, 60, 40, 5), smooth = at(flat, 60, 40, 8),
                structure = at(flat, 60, 40, 6) + at(flat, 60, 40, 7);  // lines, patterns
    if (width == 10)
        CHECK(continued + smooth < 0.25f * structure);
    else
        CHECK(structure + smooth < 0.25f * continued);

    // The same scene given as layers hides nothing: nothing is rebuilt.
    Scene layers = flat_scene(shade);
    layers.layers.push_back(std::move(layers.flat.front()));
    layers.flat.clear();
    const ImageBuf given = confidence(std::move(layers));
    const auto stats = OIIO::ImageBufAlgo::computePixelStats(given);
    for (int c = 4; c < 9; ++c)
        CHECK(stats.max[c] == 0.0f);
}

TEST_CASE("stripes behind a thin blurred pole keep their contrast")
{
    // A 10 px pole blurred to 30 px over in-focus stripes: the pole is
    // see-through, and the stripes behind it, which the flat render does
    // not hold, show in the truth. Stripes across the pole, on a slant, and
    // at an angle none of the fill's line directions has.
    const double focus = 0.5;
    const float pole_z = 1.0f / 2.9f, stripes_z = 0.5f;  // CoC -30 and 0
    const ROI pole(55, 65, 0, 80);
    const int slant = GENERATE(0, 2, 6);  // stripes fall 1 px in `slant` px
    auto stripe = [&](int x, int y) {
        const int phase = slant ? y * slant + x : y;
        const int period = slant ? 4 * slant : 4;
        return (phase / period) % 2 ? 1.0f : 0.1f;
    };
    const ImageBuf flat_result = render(flat_scene([&](int x, int y, float* rgba, float& z) {
        const bool in_pole = pole.contains(x, y);
        std::fill(rgba, rgba + 3, in_pole ? 0.5f : stripe(x, y));
        rgba[3] = 1.0f;
        z = in_pole ? pole_z : stripes_z;
    }), focus);

    Scene complete = flat_scene([&](int x, int y, float* rgba, float& z) {
        std::fill(rgba, rgba + 3, stripe(x, y));
        rgba[3] = 1.0f;
        z = stripes_z;
    });
    complete.layers.push_back(std::move(complete.flat.front()));
    complete.flat.clear();
    Layer front { "pole", zero_image(pole, 4), zero_image(pole, 1) };
    OIIO::ImageBufAlgo::fill(front.color, { 0.5f, 0.5f, 0.5f, 1.0f });
    OIIO::ImageBufAlgo::fill(front.depth, { pole_z });
    front.color.specmod().alpha_channel = 3;
    complete.layers.push_back(std::move(front));
    const ImageBuf truth = render(std::move(complete), focus);

    // The stripes' contrast behind the pole: the standard deviation down
    // each of the pole's columns (the blurred pole is the same all down a
    // column), averaged over the columns.
    auto contrast = [&](const ImageBuf& image) {
        double sum = 0.0;
        for (int x = pole.xbegin; x < pole.xend; ++x) {
            double s = 0.0, s2 = 0.0;
            const int n = 48;
            for (int y = 16; y < 16 + n; ++y) {
                const double v = image.getchannel(x, y, 0, 0);
                s += v;
                s2 += v * v;
            }
            sum += std::sqrt(std::max(0.0, s2 / n - (s / n) * (s / n)));
        }
        return sum / pole.width();
    };
    INFO("slant " << slant << ", contrast: flat " << contrast(flat_result) << ", layered "
                  << contrast(truth));
    CHECK(contrast(flat_result) >= 0.5 * contrast(truth));
}

namespace {

/// A deep render of size 120x80: a striped wall at 25 m, and over the left
/// half, a uniform fog from 2 m to 20 m of alpha 0.6, as one volume sample
/// a pixel (`thin` 0), as `thin` point samples of the same alpha between
/// them evenly through it, or (-1) as one point sample at 11 m.
Scene fog_scene(int thin)
{
    Scene scene;
    scene.spec = OIIO::ImageSpec(120, 80, 4, OIIO::TypeFloat);
    DeepImage deep;
    deep.name = "fog";
    deep.roi = ROI(0, 120, 0, 80);
    const float alpha = 0.6f, shade = 0.3f, near = 2.0f, far = 20.0f;
    for (int y = 0; y < 80; ++y)
        for (int x = 0; x < 120; ++x) {
            deep.offsets.push_back(deep.samples.size());
            if (x < 60 && thin <= 0)
                deep.samples.push_back({ shade * alpha, shade * alpha, shade * alpha, alpha,
                                         thin < 0 ? 0.5f * (near + far) : near,
                                         thin < 0 ? 0.5f * (near + far) : far });
            for (int i = 0; x < 60 && i < thin; ++i) {
                const float a = float(-std::expm1(std::log1p(-alpha) / thin));
                const float z = near + (far - near) * (i + 0.5f) / float(thin);
                deep.samples.push_back({ shade * a, shade * a, shade * a, a, z, z });
            }
            const float wall = (x / 4) % 2 ? 1.0f : 0.1f;
            deep.samples.push_back({ wall, wall, wall, 1.0f, 25.0f, 25.0f });
        }
    deep.offsets.push_back(deep.samples.size());
    scene.deep.push_back(std::move(deep));
    return scene;
}

}  // namespace

TEST_CASE("a checker behind a thin pole continues with its period")
{
    // Checks 15 px wide, 10 high; a pole over x 56-63 hides a check's edge
    // (at x 60). A line between the hole's two sides ramps from one check's
    // colour to the other's; a copy from one period along the row puts the
    // edge where it is. A light one period before the pole must not be
    // copied behind it.
    const ROI pole(56, 64, 0, 80), light(26, 34, 36, 44);
    auto check = [](int x, int y) { return (x / 15 + y / 10) % 2 ? 0.9f : 0.1f; };
    Scene scene = flat_scene([&](int x, int y, float* rgba, float& z) {
        const bool in_pole = pole.contains(x, y);
        std::fill(rgba, rgba + 3, in_pole ? 0.05f : light.contains(x, y) ? 50.0f : check(x, y));
        rgba[3] = 1.0f;
        z = in_pole ? 1.0f / 2.9f : 0.5f;  // CoC -30 and 0 at focus 0.5
    });
    const auto [layers, slicing] = cut(std::move(scene), synthetic_camera(0.5));
    const Layer& back = layers.layers.front();
    double worst = 0.0;
    for (int y = 4; y < 76; ++y)
        for (int x = pole.xbegin; x < pole.xend; ++x)
            worst = std::max(worst, double(std::abs(back.color.getchannel(x, y, 0, 0)
                                                    - check(x, y))));
    INFO("the checker behind the pole is at most " << worst << " off");
    CHECK(worst < 0.01);
    // Every pixel rebuilt is counted once, by the estimate that made it:
    // here, behind the pole, mostly patterns.
    int64_t marked = 0;
    for (const Layer& layer : layers.layers)
        if (layer.rebuilt.initialized())
            for (OIIO::ImageBuf::ConstIterator<uint8_t> p(layer.rebuilt); !p.done(); ++p)
                marked += p[0] > 0.0f;
    const RebuiltPixels& rebuilt = slicing.rebuilt;
    INFO("patterns " << rebuilt.patterns << ", lines " << rebuilt.lines << ", smooth "
                     << rebuilt.smooth << ", continued " << rebuilt.continued);
    CHECK(rebuilt.total() == marked);
    CHECK(rebuilt.patterns > 3 * (rebuilt.lines + rebuilt.smooth));
}

TEST_CASE("a checker behind a wide card continues with its period, and curved stripes do not streak")
{
    // A card 60 px wide over a checker of checks 15 px wide: each row
    // behind it is copied from a period or more along, as the rows beside
    // it are (the smooth fill and lines alone leave it 0.6 rms off), also
    // where the card's blur (CoC -24) lets lines reach only 48 px across.
    // Arcs of stripes behind the same card match a shift on one row by
    // chance and another on the next: copies the rows beside them do not
    // share cut the arcs into horizontal streaks: steps down the columns
    // 2.4 times the arcs' own (1.6 times with copies weighed by the rows
    // beside them, 1.5 without wide copies).
    const ROI card(120, 180, 0, 100);
    auto checker = [](int x, int y) { return (x / 15 + y / 10) % 2 ? 0.9f : 0.1f; };
    auto arcs = [](int x, int y) {
        return int(std::hypot(x - 150.0, y - 130.0) / 8.0) % 2 ? 0.9f : 0.1f;
    };
    // At focus 0.5, 1 / 4.1 is CoC -70 and 1 / 2.72 CoC -24.
    // (Not a structured binding: C++17 lambdas cannot capture one.)
    for (const auto& wall_and_card : { std::pair { false, 1.0f / 4.1f },
                                       std::pair { false, 1.0f / 2.72f },
                                       std::pair { true, 1.0f / 4.1f } }) {
        const bool curved = wall_and_card.first;
        const float card_depth = wall_and_card.second;
        auto wall = [&](int x, int y) { return curved ? arcs(x, y) : checker(x, y); };
        Scene scene = flat_scene([&](int x, int y, float* rgba, float& z) {
            const bool in_card = card.contains(x, y);
            std::fill(rgba, rgba + 3, in_card ? 0.05f : wall(x, y));
            rgba[3] = 1.0f;
            z = in_card ? card_depth : 0.5f;
        }, 300, 100);
        const LayeredScene layers = cut(std::move(scene), synthetic_camera(0.5)).layers;
        const Layer& back = layers.layers.front();
        double squares = 0.0, steps = 0.0, wall_steps = 0.0;
        int count = 0;
        for (int y = 4; y < 96; ++y)
            for (int x = card.xbegin; x < card.xend; ++x, ++count) {
                const float here = back.color.getchannel(x, y, 0, 0);
                squares += std::pow(here - wall(x, y), 2);
                steps += std::abs(back.color.getchannel(x, y + 1, 0, 0) - here);
                wall_steps += std::abs(wall(x, y + 1) - wall(x, y));
            }
        const double rms = std::sqrt(squares / count);
        INFO((curved ? "arcs" : "checker") << " behind the card at depth " << card_depth << ": "
                                           << rms << " rms off; steps down the columns "
                                           << steps << " against the wall's " << wall_steps);
        if (curved)
            CHECK(steps < 2.0 * wall_steps);
        else
            CHECK(rms < 0.25);
    }
}

TEST_CASE("a light half behind a pole is continued behind it as the disc it is")
{
    // A light of radius 5, 20 times the wall's brightness, antialiased, its
    // left half behind a pole (CoC -30): the lens sees around the pole to
    // the whole disc. The fill alone continues a blur of the light's seen
    // half; the disc fitted to that half's antialiased rim holds the
    // light's whole energy, and around it the wall is the wall.
    const double cx = 62.0, cy = 40.0, radius = 5.0;
    const float wall = 0.3f, light = 6.0f;
    auto cover = [&](int x, int y) {
        int inside = 0;
        for (int j = 0; j < 8; ++j)
            for (int i = 0; i < 8; ++i)
                inside += std::hypot(x + (i + 0.5) / 8 - cx, y + (j + 0.5) / 8 - cy) < radius;
        return inside / 64.0f;
    };
    const ROI pole(54, 62, 0, 80);
    Scene scene = flat_scene([&](int x, int y, float* rgba, float& z) {
        const bool in_pole = pole.contains(x, y);
        const float c = cover(x, y);
        std::fill(rgba, rgba + 3, in_pole ? 0.05f : c * light + (1 - c) * wall);
        rgba[3] = 1.0f;
        z = in_pole ? 1.0f / 2.9f : 0.5f;  // CoC -30 and 0 at focus 0.5
    });
    const auto [layers, slicing] = cut(std::move(scene), synthetic_camera(0.5));
    const Layer& back = layers.layers.front();
    double energy = 0.0, true_energy = 0.0, worst_wall = 0.0;
    for (int y = 30; y < 50; ++y)
        for (int x = pole.xbegin; x < pole.xend; ++x) {
            const float c = cover(x, y);
            energy += back.color.getchannel(x, y, 0, 0) - wall;
            true_energy += c * (light - wall);
            if (std::hypot(x + 0.5 - cx, y + 0.5 - cy) > radius + 1.0)
                worst_wall = std::max(worst_wall,
                                      double(std::abs(back.color.getchannel(x, y, 0, 0) - wall)));
        }
    INFO("the light behind the pole: " << energy << " against " << true_energy
                                       << "; the wall around it at most " << worst_wall << " off");
    CHECK(std::abs(energy - true_energy) < 0.05 * true_energy);
    CHECK(worst_wall < 0.05);
    CHECK(slicing.rebuilt.continued > 0);
}

TEST_CASE("a light in an infinitely far sky, half behind a pole, is continued without NaNs")
{
    // A star beside a pole: the light and the sky around it at infinite
    // depth. Blending the disc over its surroundings took 0 times an
    // infinite weighted depth, NaN, in 100 pixels.
    const ROI pole(54, 62, 0, 80);
    Scene scene = flat_scene([&](int x, int y, float* rgba, float& z) {
        const bool in_pole = pole.contains(x, y);
        const bool in_light = std::hypot(x + 0.5 - 62.0, y + 0.5 - 40.0) < 5.0;
        std::fill(rgba, rgba + 3, in_pole ? 0.05f : in_light ? 6.0f : 0.3f);
        rgba[3] = 1.0f;
        z = in_pole ? 1.0f / 2.9f : INFINITY;
    });
    const auto [layers, slicing] = cut(std::move(scene), synthetic_camera(0.5));
    CHECK(slicing.rebuilt.continued > 0);
    int64_t nans = 0;
    for (const Layer& layer : layers.layers)
        for (const ImageBuf* image : { &layer.color, &layer.depth })
            for (OIIO::ImageBuf::ConstIterator<float> p(*image); !p.done(); ++p)
                for (int c = 0; c < image->nchannels(); ++c)
                    nans += std::isnan(p[c]);
    CHECK(nans == 0);
}

TEST_CASE("a volume deep sample is spread over the depth it spans")
{
    // Volume samples (ZBack > Z), as Houdini, Karma or RenderMan write fog,
    // are the limit of thin samples through them: a fog from 2 m to 20 m
    // (CoC -5.8 to +9.8 px) is the same as 1024 thin samples, layer by
    // layer. Each piece of it between the layers' boundaries went to the
    // layers as a point at its middle depth: 2.3e-3 off.
    LayeringOptions eight;
    eight.layers = 8;
    const ImageBuf volume = render(fog_scene(0), 3.0, eight);
    auto worst = [&](const ImageBuf& other) {
        float most = 0.0f;
        for (int y = 0; y < 80; ++y)
            for (int x = 0; x < 120; ++x)
                for (int c = 0; c < 4; ++c)
                    most = std::max(most, std::abs(volume.getchannel(x, y, 0, c)
                                                   - other.getchannel(x, y, 0, c)));
        return most;
    };
    const float fine = worst(render(fog_scene(1024), 3.0, eight)),
                coarse = worst(render(fog_scene(64), 3.0, eight)),
                one_depth = worst(render(fog_scene(-1), 3.0, eight));
    WARN("fog as one volume sample, at most this far from 1024 thin samples: "
         << fine << "; from 64 (2.4 px of CoC apart at 2 m): " << coarse
         << "; a point sample at its middle depth: " << one_depth);
    CHECK(fine < 1e-3f);
    CHECK(one_depth > 10.0f * fine);
}

TEST_CASE("a volume deep sample keeps its light where no blur tells its depths apart")
{
    // Through a pinhole every depth has CoC 0: the fog is one point.
    Camera pinhole = synthetic_camera(3.0);
    pinhole.fstop = INFINITY;
    const LayeredScene layers = cut(fog_scene(0), pinhole).layers;
    float out[4];
    composite_pixel(layers.layers, 10, 10, out);
    // The fog (alpha 0.6, colour 0.3) over the wall's dark stripe (0.1).
    CHECK(out[0] == Approx(0.3f * 0.6f + 0.4f * 0.1f).epsilon(1e-4));
    CHECK(out[3] == Approx(1.0f));
}
