// Layered depth of field on a two-layer scene: partial occlusion and no
// intensity leakage, where the gather baseline shows both artifacts.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>

#include <OpenImageIO/imagebufalgo.h>

#include <defocus/composite/deep_result.h>
#include <defocus/composite/defocus_layers.h>
#include <defocus/focus/focus_map.h>
#include <defocus/spread/spread.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using OIIO::ImageBuf;
using OIIO::ROI;

namespace {

// A red opaque square at depth 1 in front of a green striped wall at 10.
const ROI frame(0, 120, 0, 80);
const ROI square(40, 80, 20, 60);
const float near_z = 1.0f, far_z = 10.0f;

float wall_green(int x) { return 0.2f + 0.6f * float((x / 4) % 2); }

Scene two_layer_scene()
{
    Scene scene;
    scene.source = "synthetic";
    scene.spec = OIIO::ImageSpec(120, 80, 4, OIIO::TypeFloat);
    Layer wall { "wall", zero_image(frame, 4), zero_image(frame, 1) };
    Layer card { "card", zero_image(square, 4), zero_image(square, 1) };
    for (int y = frame.ybegin; y < frame.yend; ++y)
        for (int x = frame.xbegin; x < frame.xend; ++x) {
            const float green[4] = { 0, wall_green(x), 0, 1 };
            wall.color.setpixel(x, y, green);
            wall.depth.setpixel(x, y, &far_z);
        }
    OIIO::ImageBufAlgo::fill(card.color, { 1.0f, 0.0f, 0.0f, 1.0f });
    OIIO::ImageBufAlgo::fill(card.depth, { near_z });
    card.color.specmod().alpha_channel = wall.color.specmod().alpha_channel = 3;
    scene.layers.push_back(std::move(card));  // out of order on purpose
    scene.layers.push_back(std::move(wall));
    return scene;
}

ImageBuf layered(double focus)
{
    const Camera camera = synthetic_camera(focus);
    ImageBuf out;
    REQUIRE(defocus_layers(out, layered_scene(two_layer_scene(), camera), camera));
    return out;
}

/// The gather baseline works on the flat render: the sharp composite with
/// the depth of the front-most surface.
ImageBuf gathered(double focus)
{
    ImageBuf color = zero_image(frame, 4), depth = zero_image(frame, 1);
    for (int y = frame.ybegin; y < frame.yend; ++y)
        for (int x = frame.xbegin; x < frame.xend; ++x) {
            const bool card = square.contains(x, y);
            const float rgba[4] = { card ? 1.0f : 0.0f, card ? 0.0f : wall_green(x), 0, 1 };
            color.setpixel(x, y, rgba);
            depth.setpixel(x, y, card ? &near_z : &far_z);
        }
    ImageBuf radius, out;
    REQUIRE(coc_radius(radius, depth, CircleOfConfusion(synthetic_camera(focus), ROI(0, 120, 0, 120))));
    REQUIRE(gather(out, color, radius, box_footprint));
    return out;
}

float channel_at(const ImageBuf& image, int x, int y, int c)
{
    float p[4];
    image.getpixel(x, y, p);
    return p[c];
}

}  // namespace

TEST_CASE("a blurred background never leaks over an in-focus foreground")
{
    const ImageBuf out = layered(near_z);
    // Inside the sharp card: exactly the card, no wall light.
    for (int y = square.ybegin; y < square.yend; ++y)
        for (int x = square.xbegin; x < square.xend; ++x) {
            REQUIRE(channel_at(out, x, y, 0) == Approx(1.0f).margin(1e-6));
            REQUIRE(channel_at(out, x, y, 1) == Approx(0.0f).margin(1e-6));
        }
    // Outside it: no card light either (the card is in focus).
    for (int x = 20; x < 40; ++x)
        REQUIRE(channel_at(out, x, 40, 0) == Approx(0.0f).margin(1e-6));
    // The wall itself is blurred: its 4-pixel stripes are averaged away.
    CHECK(std::abs(channel_at(out, 10, 10, 1) - channel_at(out, 12, 10, 1)) < 0.1f);
}

TEST_CASE("gathering leaks the in-focus card into the blurred wall")
{
    const ImageBuf out = gathered(near_z);
    // Wall pixels beside the card average its red into a halo.
    CHECK(channel_at(out, 36, 40, 0) > 0.1f);
}

TEST_CASE("a blurred foreground is see-through at its edges (partial occlusion)")
{
    const ImageBuf out = layered(far_z);
    // The card spreads past its silhouette...
    const float outside = channel_at(out, 36, 40, 0);
    CHECK(outside > 0.1f);
    CHECK(outside < 0.9f);
    // ...and the sharp wall shows through just inside it.
    CHECK(channel_at(out, 43, 40, 1) > 0.05f);
    // Far from the card the wall is sharp: its stripes are intact.
    CHECK(channel_at(out, 4, 5, 1) == Approx(wall_green(4)).margin(1e-5));
    CHECK(channel_at(out, 0, 5, 1) == Approx(wall_green(0)).margin(1e-5));
    // Coverage: alpha stays 1 wherever the opaque wall is.
    for (int x = 0; x < 120; x += 7)
        REQUIRE(channel_at(out, x, 40, 3) == Approx(1.0f).margin(1e-5));
}

TEST_CASE("gathering gives a blurred foreground a sharp silhouette")
{
    const ImageBuf out = gathered(far_z);
    // In-focus wall pixels only average themselves: no card beyond its edge.
    CHECK(channel_at(out, 36, 40, 0) == 0.0f);
    CHECK(channel_at(out, 39, 40, 0) == 0.0f);
}

TEST_CASE("layers are composited back to front whatever their file order")
{
    const Camera camera = synthetic_camera(near_z);
    std::vector<LayerReport> report;
    ImageBuf out;
    REQUIRE(defocus_layers(out, layered_scene(two_layer_scene(), camera), camera, {}, {},
                           OutputWindow::Input, &report));
    REQUIRE(report.size() == 2);
    CHECK(report[0].name == "wall");
    CHECK(report[1].name == "card");
    CHECK(report[1].coc_min == Approx(0.0).margin(1e-9));
    CHECK(report[0].coc_min == Approx(100.0 / 3.0 * 0.9).epsilon(1e-6));
}

TEST_CASE("a frame rendered into the last frame's image comes out as into a new one, in its "
          "buffer")
{
    const Camera camera = synthetic_camera(far_z);
    Scene scene = two_layer_scene();
    SECTION("the back layer covers the frame") {}
    SECTION("the back layer covers part of it") { scene.layers.pop_back(); }
    const LayeredScene layers = layered_scene(scene, camera);
    ImageBuf fresh;
    REQUIRE(defocus_layers(fresh, layers, camera));
    // The last frame's image: the same layout, every value stale.
    ImageBuf last(fresh.spec());
    OIIO::ImageBufAlgo::fill(last, { NAN, NAN, NAN, NAN });
    const void* buffer = last.localpixels();
    REQUIRE(defocus_layers(last, layers, camera));
    CHECK(last.localpixels() == buffer);
    const OIIO::ImageBufAlgo::CompareResults diff =
        OIIO::ImageBufAlgo::compare(last, fresh, 0.0f, 0.0f);
    CHECK(diff.nfail == 0);
    CHECK(diff.maxerror == 0.0);
}

TEST_CASE("each layer composited over the ones behind it gives the frame, and freeing the "
          "layers as they go changes no pixel, flat or deep")
{
    // Three layers, each set up only when its turn comes: a blurred wall, a
    // card in focus and a blurred card in front of part of it.
    const Camera camera = synthetic_camera(3.0);
    Scene scene = two_layer_scene();
    scene.layers[0].depth = zero_image(square, 1);
    OIIO::ImageBufAlgo::fill(scene.layers[0].depth, { 3.0f });
    const ROI near_square(20, 60, 30, 70);
    Layer near { "near", zero_image(near_square, 4), zero_image(near_square, 1) };
    OIIO::ImageBufAlgo::fill(near.color, { 0.0f, 0.0f, 0.5f, 0.5f });
    OIIO::ImageBufAlgo::fill(near.depth, { near_z });
    near.color.specmod().alpha_channel = 3;
    scene.layers.push_back(std::move(near));
    const LayeredScene layers = layered_scene(scene, camera);
    REQUIRE(layers.layers.size() == 3);

    // The reference: each layer's spread alone, composited "over" in turn.
    ImageBuf expected = zero_image(frame, 4);
    std::string error;
    REQUIRE(spread_layers_apart(layers, camera, {}, {}, OutputWindow::Input,
                                [&](size_t, const ImageBuf& spread, const ROI& window) {
                                    CHECK(window.xbegin == frame.xbegin);
                                    CHECK(window.yend == frame.yend);
                                    for (OIIO::ImageBuf::ConstIterator<float> s(spread);
                                         !s.done(); ++s) {
                                        float under[4];
                                        expected.getpixel(s.x(), s.y(), under);
                                        for (int c = 0; c < 4; ++c)
                                            under[c] = s[c] + (1.0f - s[3]) * under[c];
                                        expected.setpixel(s.x(), s.y(), under);
                                    }
                                    return true;
                                },
                                error));
    ImageBuf kept;
    std::vector<LayerReport> kept_report;
    REQUIRE(defocus_layers(kept, layers, camera, {}, {}, OutputWindow::Input, &kept_report));
    CHECK(worst_relative_error(kept, expected, 0.0, 1e-6) <= 1.0);
    // Every layer lands: the near card's blue over half of the focused
    // card's red, that card alone, and the wall's green beside it.
    CHECK(channel_at(kept, 40, 50, 2) == Approx(0.5f).margin(1e-3));
    CHECK(channel_at(kept, 40, 50, 0) == Approx(0.5f).margin(1e-3));
    CHECK(channel_at(kept, 78, 22, 0) == Approx(1.0f).margin(1e-6));
    CHECK(channel_at(kept, 100, 22, 1) > 0.2f);

    LayeredScene freed = layers;
    ImageBuf out;
    std::vector<LayerReport> report;
    REQUIRE(defocus_layers_freeing(out, freed, camera, {}, {}, OutputWindow::Input, &report));
    const OIIO::ImageBufAlgo::CompareResults diff =
        OIIO::ImageBufAlgo::compare(out, kept, 0.0f, 0.0f);
    CHECK(diff.nfail == 0);
    CHECK(diff.maxerror == 0.0);
    REQUIRE(report.size() == kept_report.size());
    for (size_t i = 0; i < freed.layers.size(); ++i) {
        CHECK(report[i].name == kept_report[i].name);
        CHECK(freed.layers[i].name == layers.layers[i].name);
        CHECK_FALSE(freed.layers[i].color.initialized());
        CHECK_FALSE(freed.layers[i].depth.initialized());
    }

    // The deep result, its samples made as each layer is spread apart.
    DeepResult deep, deep_freed;
    REQUIRE(defocus_deep(deep, layers, camera, {}, {}, OutputWindow::Input, error));
    LayeredScene freed_deep = layers;
    REQUIRE(defocus_deep_freeing(deep_freed, freed_deep, camera, {}, {}, OutputWindow::Input,
                                 error));
    CHECK(deep_freed.window == deep.window);
    REQUIRE(deep_freed.layers.size() == 3);
    REQUIRE(deep_freed.layers.size() == deep.layers.size());
    for (size_t i = 0; i < deep.layers.size(); ++i) {
        CHECK(deep_freed.layers[i].pixels == deep.layers[i].pixels);
        CHECK(deep_freed.layers[i].rgba == deep.layers[i].rgba);
        CHECK(deep_freed.layers[i].z == deep.layers[i].z);
        CHECK(deep_freed.layers[i].zback == deep.layers[i].zback);
    }
    for (const Layer& layer : freed_deep.layers) {
        CHECK_FALSE(layer.color.initialized());
        CHECK_FALSE(layer.depth.initialized());
    }
}

TEST_CASE("tent and smooth layers are composited row by row as spread_smooth spreads them")
{
    // Tent and smooth hand their rows to the compositing as they are made,
    // without an image of the layer's spread: each layer alone must come
    // out as spread_smooth's image of it, every pixel of the frame.
    const Camera camera = synthetic_camera(3.0);
    const LayeredScene layers = layered_scene(two_layer_scene(), camera);
    const CircleOfConfusion coc(camera, layers.spec.roi_full());
    for (const ApertureShape shape : { ApertureShape::Tent, ApertureShape::Smooth }) {
        SpreadOptions options;
        options.aperture.shape = shape;
        std::string error;
        size_t seen = 0;
        REQUIRE(spread_layers_apart(
            layers, camera, options, {}, OutputWindow::Input,
            [&](size_t i, const ImageBuf& spread, const ROI& window) {
                ++seen;
                const Layer& layer = layers.layers[i];
                ImageBuf radius, expected;
                REQUIRE(coc_radius(radius, layer.depth, coc));
                REQUIRE(spread_smooth(expected, layer.color, radius,
                                      shape == ApertureShape::Tent ? 2 : 3));
                for (int y = window.ybegin; y < window.yend; ++y)
                    for (int x = window.xbegin; x < window.xend; ++x)
                        for (int c = 0; c < 4; ++c) {
                            const float want = expected.roi().contains(x, y)
                                                   ? channel_at(expected, x, y, c)
                                                   : 0.0f;
                            const float got = spread.roi().contains(x, y)
                                                  ? channel_at(spread, x, y, c)
                                                  : 0.0f;
                            if (got != want)
                                FAIL_CHECK("layer " << i << " at " << x << "," << y << " channel "
                                                    << c << ": " << got << " != " << want);
                        }
                return true;
            },
            error));
        CHECK(seen == layers.layers.size());
    }
}

TEST_CASE("the focus map shows in-focus green, in front red, behind blue")
{
    auto colour_at = [](const ImageBuf& map, int x, int y, float rgba[4]) {
        map.getpixel(x, y, rgba);
    };
    float p[4];
    // Focus on the card: the card is green, the wall behind it blue.
    ImageBuf map;
    const Camera camera_near_z = synthetic_camera(near_z);
    REQUIRE(focus_map(map, layered_scene(two_layer_scene(), camera_near_z), camera_near_z));
    colour_at(map, 60, 40, p);
    CHECK(p[1] == 1.0f);
    CHECK(p[0] == 0.0f);
    colour_at(map, 10, 10, p);
    CHECK(p[2] > 0.5f);
    CHECK(p[0] == 0.0f);
    CHECK(p[1] == 0.0f);
    // Focus on the wall: the card is red, the wall green.
    const Camera camera_far_z = synthetic_camera(far_z);
    REQUIRE(focus_map(map, layered_scene(two_layer_scene(), camera_far_z), camera_far_z));
    colour_at(map, 60, 40, p);
    CHECK(p[0] > 0.5f);
    CHECK(p[1] == 0.0f);
    colour_at(map, 10, 10, p);
    CHECK(p[1] == 1.0f);
    // Where the blur reaches the max, the colour is whitened.
    Camera clamped = synthetic_camera(far_z);
    clamped.max_blur_px = 10;
    REQUIRE(focus_map(map, layered_scene(two_layer_scene(), clamped), clamped));
    colour_at(map, 60, 40, p);
    CHECK(p[0] > 0.9f);
    CHECK(p[1] >= 0.5f);
    CHECK(p[2] >= 0.5f);
}

TEST_CASE("antialiased edges without a depth take their covered neighbours' depth")
{
    // One row: an opaque object at 2 m, its antialiased edge written with
    // the renderer's "nothing" depth, then empty; and a half-covered pixel
    // of sky, whose neighbours are sky too.
    const ROI row(0, 6, 0, 1);
    Layer layer { "edge", zero_image(row, 4), zero_image(row, 1) };
    const float alpha[6] = { 1.0f, 1.0f, 0.4f, 0.0f, 0.5f, 1.0f };
    const float depth[6] = { 2.0f, 2.0f, 1e10f, 1e10f, 1e10f, 1e10f };
    for (int x = 0; x < 6; ++x) {
        const float c[4] = { 0.5f * alpha[x], 0.5f * alpha[x], 0.5f * alpha[x], alpha[x] };
        layer.color.setpixel(x, 0, c);
        layer.depth.setpixel(x, 0, &depth[x]);
    }
    Scene scene;
    scene.layers.push_back(layer);
    const PixelCounts fixed = sanitize(scene);
    CHECK(fixed.edge_depth == 1);
    auto z = [&](int x) { return scene.layers[0].depth.getchannel(x, 0, 0, 0); };
    CHECK(z(2) == 2.0f);    // the edge belongs to the object beside it
    CHECK(z(4) == 1e10f);   // no neighbour has a depth: the sky stays the sky
    CHECK(z(5) == 1e10f);   // fully covered: a depth of its own
}

namespace {

/// One layer over `roi`: `color` everywhere (or only at `point`), at depth z.
Scene one_layer(const ROI& roi, float z, const float* color, const int* point = nullptr)
{
    Scene scene;
    scene.source = "synthetic";
    scene.spec = OIIO::ImageSpec(roi.width(), roi.height(), 4, OIIO::TypeFloat);
    Layer layer { "layer", zero_image(roi, 4), zero_image(roi, 1) };
    if (point)
        layer.color.setpixel(point[0], point[1], color);
    else
        OIIO::ImageBufAlgo::fill(layer.color, { color[0], color[1], color[2], color[3] });
    OIIO::ImageBufAlgo::fill(layer.depth, { z });
    layer.color.specmod().alpha_channel = 3;
    scene.layers.push_back(std::move(layer));
    return scene;
}

/// Pixels lit in channel c of an impulse's spread, weighted by coverage.
double lit_area(const ImageBuf& image, int c)
{
    double peak = 0.0, sum = 0.0;
    for (ImageBuf::ConstIterator<float> it(image); !it.done(); ++it) {
        peak = std::max(peak, double(it[c]));
        sum += it[c];
    }
    return sum / peak;
}

}  // namespace

TEST_CASE("axial chromatic aberration: red and blue bokeh of the predicted size, light kept, "
          "nothing in focus fringed")
{
    const ROI roi(0, 101, 0, 101);
    const float white[4] = { 1, 1, 1, 1 };
    const int centre[2] = { 50, 50 };
    Camera camera = synthetic_camera(1.0);
    camera.axial_ca = 0.2;
    SpreadOptions exact;
    exact.exact_shape = true;
    // c = f^2 / (N s) W (1/z_f - 1/z) = 28.06 px per dioptre over 101 px.
    const double k = 0.1 * (100.0 / 36.0) * 101.0;
    // Behind the focus (z = 10), red and blue blur 0.8 times green's; in
    // front (z = 0.5), 1.2 times.
    for (const auto& [z, c] : { std::pair { 10.0f, k * 0.9 }, { 0.5f, -k } }) {
        const double scale = c > 0 ? 0.8 : 1.2;
        ImageBuf out;
        REQUIRE(defocus_layers(out, layered_scene(one_layer(roi, z, white, centre), camera),
                               camera, exact));
        INFO("depth " << z);
        const double r = 0.5 * std::abs(c);
        CHECK(lit_area(out, 1) == Approx(M_PI * r * r).epsilon(0.02));
        CHECK(lit_area(out, 3) == Approx(M_PI * r * r).epsilon(0.02));  // alpha is green's
        for (int ch : { 0, 2 })
            CHECK(lit_area(out, ch) == Approx(M_PI * r * r * scale * scale).epsilon(0.02));
        for (int ch = 0; ch < 4; ++ch)
            CHECK(channel_sum(out, ch) == Approx(1.0).epsilon(1e-6));
    }

    // A grey edge: in focus no fringe at all; out of focus, red and blue
    // differ from green across it.
    Scene edge = one_layer(roi, 1.0f, white);
    OIIO::ImageBufAlgo::fill(edge.layers[0].color, { 0.2f, 0.2f, 0.2f, 1.0f },
                             ROI(50, 101, 0, 101));
    ImageBuf sharp, blurred;
    REQUIRE(defocus_layers(sharp, layered_scene(edge, camera), camera));
    float worst = 0.0f;
    for (ImageBuf::ConstIterator<float> it(sharp); !it.done(); ++it)
        worst = std::max({ worst, std::abs(it[0] - it[1]), std::abs(it[2] - it[1]) });
    CHECK(worst == 0.0f);
    OIIO::ImageBufAlgo::fill(edge.layers[0].depth, { 0.5f });
    REQUIRE(defocus_layers(blurred, layered_scene(edge, camera), camera));
    float p[4];
    blurred.getpixel(40, 50, p);  // on the bright side: red and blue, wider, lose more
    CHECK(p[0] < p[1] - 0.01f);
    CHECK(p[2] == p[0]);
}

TEST_CASE("lateral chromatic aberration: red and blue land magnified about the optical centre, "
          "light kept")
{
    const ROI roi(0, 101, 0, 101);
    const float white[4] = { 1, 1, 1, 1 };
    const int light[2] = { 80, 30 };
    Camera camera = synthetic_camera(1.0);
    camera.lateral_ca = 0.02;
    camera.axis_pixel = Imath::V2d(40, 60);  // the axis off the frame's centre
    const double ox = 40.5, oy = 60.5;
    auto centroid = [](const ImageBuf& image, int c) {
        double sum = 0.0, sx = 0.0, sy = 0.0;
        for (ImageBuf::ConstIterator<float> it(image); !it.done(); ++it) {
            sum += it[c];
            sx += it[c] * (it.x() + 0.5);
            sy += it[c] * (it.y() + 0.5);
        }
        return std::array<double, 3> { sx / sum, sy / sum, sum };
    };
    // In focus, and out of focus behind it.
    for (const float z : { 1.0f, 3.0f }) {
        ImageBuf out;
        REQUIRE(defocus_layers(out, layered_scene(one_layer(roi, z, white, light), camera),
                               camera));
        INFO("depth " << z);
        const auto green = centroid(out, 1);
        CHECK(green[0] == Approx(80.5).margin(1e-6));
        CHECK(green[1] == Approx(30.5).margin(1e-6));
        for (const auto& [c, m] : { std::pair { 0, 1.02 }, { 2, 0.98 } }) {
            const auto at = centroid(out, c);
            CHECK(at[0] == Approx(ox + (80.5 - ox) * m).margin(1e-6));
            CHECK(at[1] == Approx(oy + (30.5 - oy) * m).margin(1e-6));
            CHECK(at[2] == Approx(1.0).epsilon(1e-6));
        }
        CHECK(centroid(out, 3)[2] == Approx(1.0).epsilon(1e-6));
    }
    // The optical centre itself does not move, in any colour; an opaque
    // in-focus layer stays opaque and keeps its colour within the frame.
    const int axis[2] = { 40, 60 };
    ImageBuf out;
    REQUIRE(defocus_layers(out, layered_scene(one_layer(roi, 1.0f, white, axis), camera), camera));
    float p[4];
    out.getpixel(40, 60, p);
    CHECK(p[0] == Approx(1.0f).epsilon(1e-6));
    CHECK(p[2] == Approx(1.0f).epsilon(1e-6));
    const float grey[4] = { 0.5f, 0.5f, 0.5f, 1.0f };
    REQUIRE(defocus_layers(out, layered_scene(one_layer(roi, 1.0f, grey), camera), camera));
    out.getpixel(45, 55, p);
    CHECK(p[3] == Approx(1.0f).epsilon(1e-6));
    CHECK(p[0] == Approx(0.5f / (1.02f * 1.02f)).epsilon(1e-3));  // the same light, spread wider
    CHECK(p[2] == Approx(0.5f / (0.98f * 0.98f)).epsilon(1e-3));
}
