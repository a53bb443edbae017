// Sub-aperture compositing against the thin lens by brute force: a near
// object hides different parts of a far one from different points of the
// lens.
#include <catch2/catch.hpp>

#include <cmath>
#include <functional>

#include <Imath/ImathVec.h>
#include <OpenImageIO/imagebufalgo.h>

#include <defocus/composite/data_channels.h>
#include <defocus/composite/defocus_layers.h>

#include "test_support.h"
#include "thin_lens.h"

using namespace defocus;
using namespace defocus_test;
using OIIO::ImageBuf;
using OIIO::ROI;

namespace {

/// 85 mm f/1.4 focused at 3 m over a 600 px wide frame: a point at 1 m has
/// a CoC 57 px across, one at 10 m 20 px.
Camera lens_camera()
{
    Camera camera;
    camera.focal_length_mm = 85;
    camera.fstop = 1.4;
    camera.sensor_width_mm = 36;
    camera.focus_distance = 3;
    return camera;
}

/// The frame: a 96 × 96 data window in the middle of a 600 × 400 display.
const ROI frame(252, 348, 152, 248, 0, 1, 0, 4);
const int centre_x = 300, centre_y = 200;

using Shade = std::function<void(int x, int y, float* rgba)>;

/// Planar layers over the frame, as the engine and the thin lens take them.
struct Stack {
    LayeredScene scene;
    /// The layers as the thin lens sees green, and red and blue (their
    /// radii under the camera's axial aberration, set before they are
    /// added).
    std::vector<LensLayer> lens, lens_red_blue;

    ROI data;
    Camera camera = lens_camera();

    /// The display window 600 × 400 from (`display_x`, 0), the data window
    /// `data_window`.
    explicit Stack(int display_x = 0, const ROI& data_window = frame)
        : data(data_window)
    {
        scene.source = "synthetic";
        scene.spec = OIIO::ImageSpec(data.width(), data.height(), 4, OIIO::TypeFloat);
        scene.spec.x = data.xbegin;
        scene.spec.y = data.ybegin;
        scene.spec.full_x = display_x;
        scene.spec.full_y = 0;
        scene.spec.full_width = 600;
        scene.spec.full_height = 400;
    }

    /// Adds a layer at `depth` (add them back to front).
    void add(const char* name, float depth, const Shade& shade)
    {
        add(name, [=](int, int) { return depth; }, shade);
    }

    /// Adds a layer at depth_at(x, y) a pixel.
    void add(const char* name, const std::function<float(int x, int y)>& depth_at,
             const Shade& shade)
    {
        const CircleOfConfusion coc(camera, scene.spec.roi_full());
        Layer layer { name, zero_image(data, 4), zero_image(data, 1) };
        LensLayer seen { zero_image(data, 4), zero_image(data, 1) };
        LensLayer seen_red_blue { zero_image(data, 4), zero_image(data, 1) };
        layer.color.specmod().alpha_channel = 3;
        for (int y = data.ybegin; y < data.yend; ++y)
            for (int x = data.xbegin; x < data.xend; ++x) {
                float rgba[4] = { 0, 0, 0, 0 };
                shade(x, y, rgba);
                const float depth = depth_at(x, y);
                const float radius = float(0.5 * coc.diameter(depth, x, y)),
                            radius_red_blue
                            = float(0.5 * coc.diameter(depth, x, y, CocChannel::RedBlue));
                layer.color.setpixel(x, y, rgba);
                layer.depth.setpixel(x, y, &depth);
                seen.color.setpixel(x, y, rgba);
                seen.radius.setpixel(x, y, &radius);
                seen_red_blue.color.setpixel(x, y, rgba);
                seen_red_blue.radius.setpixel(x, y, &radius_red_blue);
            }
        scene.layers.push_back(std::move(layer));
        lens.push_back(std::move(seen));
        lens_red_blue.push_back(std::move(seen_red_blue));
        order_layers(scene, coc);
    }

    ImageBuf engine(int cells, OutputWindow window = OutputWindow::Input,
                    SubApertureReport* report = nullptr) const
    {
        SpreadOptions spread;
        spread.aperture_cells = cells;
        ImageBuf out;
        SpreadStats stats;
        REQUIRE(defocus_layers(out, scene, camera, spread, {}, window, nullptr, &stats));
        if (report)
            *report = stats.cells;
        return out;
    }
};

/// Lights 20 times brighter than the wall around them (where `lit` says),
/// at 10 m, behind vertical bars at 1 m, 4 px wide every 16 px; `bars`
/// says which columns of bars there are (by index from the centre).
Stack fence(const std::function<bool(int bar)>& bars, const std::function<bool(int x, int y)>& lit,
            Stack stack)
{
    stack.add("light", 10.0f, [&](int x, int y, float* rgba) {
        const bool light = lit(x, y);
        rgba[0] = rgba[1] = rgba[2] = light ? 1.0f : 0.05f;
        rgba[3] = 1.0f;
    });
    stack.add("bars", 1.0f, [&](int x, int, float* rgba) {
        const int from_centre = x - centre_x + 8;  // bar 0 covers the centre
        const int bar = from_centre >= 0 ? from_centre / 16 : -((-from_centre + 15) / 16);
        if (bars(bar) && from_centre - bar * 16 >= 6 && from_centre - bar * 16 < 10) {
            rgba[0] = rgba[1] = rgba[2] = 0.01f;
            rgba[3] = 1.0f;
        }
    });
    return stack;
}

/// The fence before one light at the centre, or `light_x` across; the
/// display window from `display_x`.
Stack fence(const std::function<bool(int bar)>& bars, int light_x = centre_x, int display_x = 0)
{
    return fence(
        bars,
        [=](int x, int y) { return std::hypot(x + 0.5 - light_x, y + 0.5 - centre_y) < 3.0; },
        Stack(display_x));
}

/// Adds dark opaque vertical bars `width` px wide every 16 px at `depth`.
void add_bars(Stack& stack, float depth, int width)
{
    stack.add("bars", depth, [=](int x, int, float* rgba) {
        if ((x - centre_x + 256) % 16 < width) {
            rgba[0] = rgba[1] = rgba[2] = 0.01f;
            rgba[3] = 1.0f;
        }
    });
}

/// The light's bokeh: its 20 px CoC around the centre.
const ROI bokeh(centre_x - 12, centre_x + 12, centre_y - 12, centre_y + 12, 0, 1, 0, 4);

/// The display window from here puts the optical centre 250 px left of the
/// light, 360 px from the display's corners.
const int off_centre_display_x = -250;

/// The fence before the light, off the optical centre.
Stack off_centre_fence()
{
    return fence([](int) { return true; }, centre_x, off_centre_display_x);
}

/// The lens as the barrel clips it with --cateye 1 over the off-centre
/// display (Camera::cateye): the unit disc around an offset towards the
/// optical centre, 1 at the display's corners, at the pixel the light
/// reaches.
LensClip full_cateye_clip()
{
    const Imath::V2d optical_centre(off_centre_display_x + 300.0, 200.0);
    const double corner = std::hypot(300.0, 200.0);
    return [=](double ux, double uy, int x, int y) {
        const Imath::V2d offset = (optical_centre - Imath::V2d(x + 0.5, y + 0.5)) / corner;
        return (Imath::V2d(ux, uy) - offset).length2() <= 1.0;
    };
}

/// PSNR against `exact` over the light's bokeh with automatic cells, and
/// with one.
struct BokehScores {
    double cells, one;
};

BokehScores bokeh_scores(const Stack& stack, const ImageBuf& exact)
{
    return { psnr_over(stack.engine(0), exact, bokeh), psnr_over(stack.engine(1), exact, bokeh) };
}

}  // namespace

TEST_CASE("a fence before a far light cuts its shadow into the light's bokeh")
{
    const Stack stack = fence([](int) { return true; });
    const auto [cells, one] = bokeh_scores(stack, thin_lens(stack.lens, bokeh));
    WARN("fence, against the thin lens over the light's bokeh: " << cells
         << " dB with cells, " << one << " dB with one cell");
    CHECK(cells >= 35.0);
    CHECK(one < cells - 5.0);
}

TEST_CASE("a cat's eye clips every part of the lens alike: the fence's shadow in the clipped bokeh")
{
    // The light 250 px right of the optical centre, 360 px from the
    // display's corners: with the full clip the barrel leaves the part of
    // the lens within a unit disc 0.69 to the left of the aperture's centre
    // (Camera::cateye), at every pixel the light reaches, for both layers.
    Stack stack = off_centre_fence();
    stack.camera.cateye = 1.0;
    const LensClip clip = full_cateye_clip();
    const auto [cells, one] = bokeh_scores(stack, thin_lens(stack.lens, bokeh, 48, clip));
    WARN("fence before a clipped bokeh, against the thin lens: " << cells << " dB with cells, "
         << one << " dB with one cell");
    // 30.3 dB while the cells took the unclipped lens's shares, 34.4 while
    // the engine clipped the near fence's footprints towards the optical
    // centre as it does a far one's. What is left is mostly the engine's
    // own clip taken where the light leaves, not where it lands: the light
    // alone scores 40.9 dB here.
    CHECK(cells >= 36.0);
    CHECK(one < cells - 4.0);
}

TEST_CASE("a cat's eye clips a near light's bokeh on the side away from the optical centre")
{
    // A light at 1 m, in front of the focus, 250 px right of the optical
    // centre. Its light leaves lens point u for s + rho u with rho < 0: the
    // bokeh is the clipped lens turned half a turn, its clipped side facing
    // away from the optical centre, where a far light's faces it.
    Stack stack(off_centre_display_x);
    stack.camera.cateye = 1.0;
    stack.add("light", 1.0f, [](int x, int y, float* rgba) {
        if (std::hypot(x + 0.5 - centre_x, y + 0.5 - centre_y) < 3.0)
            rgba[0] = rgba[1] = rgba[2] = rgba[3] = 1.0f;
    });
    const LensClip clip = full_cateye_clip();
    const ROI near_bokeh(centre_x - 36, centre_x + 36, centre_y - 36, centre_y + 36, 0, 1, 0, 4);
    const ImageBuf exact = thin_lens(stack.lens, near_bokeh, 48, clip);
    const double score = psnr_over(stack.engine(1), exact, near_bokeh);
    WARN("a near light's clipped bokeh against the thin lens: " << score << " dB");
    // 5.5 dB with the clip facing the optical centre; what is left is the
    // clip taken where the light leaves, not where it lands (it changes by
    // a sixth of the lens across this 57 px bokeh).
    CHECK(score >= 24.0);
}

TEST_CASE("under axial aberration red and blue are cut by the fence as their own blur says")
{
    // Red and blue blur 30% less than green behind the focus and more in
    // front of it (Camera::axial_ca): the far light's bokeh is smaller in
    // them, the bars' shadows wider. The thin lens sees each colour through
    // its own radii, alpha included, as the engine composites them.
    Stack aberrated;
    aberrated.camera.axial_ca = 0.3;
    const Stack stack = fence(
        [](int) { return true; },
        [](int x, int y) { return std::hypot(x + 0.5 - centre_x, y + 0.5 - centre_y) < 3.0; },
        aberrated);
    const ImageBuf green = thin_lens(stack.lens, bokeh),
                   red_blue = thin_lens(stack.lens_red_blue, bokeh);
    ImageBuf exact;
    exact.copy(green);
    for (OIIO::ImageBuf::Iterator<float> it(exact, bokeh); !it.done(); ++it)
        for (int c : { 0, 2 })
            it[c] = red_blue.getchannel(it.x(), it.y(), 0, c);
    const auto [cells, one] = bokeh_scores(stack, exact);
    WARN("fence under axial aberration, against the thin lens: " << cells << " dB with cells, "
         << one << " dB with one cell");
    // 34.2 dB, below one cell, while red and blue took green's cells.
    CHECK(cells >= 35.0);
    CHECK(one < cells - 5.0);
}

TEST_CASE("under lateral aberration the fence's shadow is magnified with red and blue")
{
    // The light 250 px right of the optical centre: red lands 1% farther
    // from it and blue 1% nearer (Camera::lateral_ca), 2.5 px each way. The
    // thin lens's picture, each of red and blue magnified as the camera
    // magnifies it: a pixel's light spread bilinearly where it lands.
    Stack stack = off_centre_fence();
    stack.camera.lateral_ca = 0.01;
    ROI around = bokeh;
    around.xbegin -= 8;
    around.xend += 8;
    const ImageBuf seen = thin_lens(stack.lens, around);
    ImageBuf exact;
    exact.copy(seen);
    const double optical_x = off_centre_display_x + 300.0, optical_y = 200.0;
    for (const int c : { 0, 2 }) {
        const double m = c == 0 ? 1.01 : 0.99;
        for (OIIO::ImageBuf::Iterator<float> it(exact); !it.done(); ++it)
            it[c] = 0.0f;
        for (OIIO::ImageBuf::ConstIterator<float> it(seen); !it.done(); ++it) {
            // Where the pixel's centre lands, as the corner of a pixel.
            const double x = optical_x + (it.x() + 0.5 - optical_x) * m - 0.5,
                         y = optical_y + (it.y() + 0.5 - optical_y) * m - 0.5;
            const int ix = int(std::floor(x)), iy = int(std::floor(y));
            const double fx = x - ix, fy = y - iy;
            for (int k = 0; k < 4; ++k) {
                const int px = ix + (k & 1), py = iy + (k >> 1);
                if (!around.contains(px, py))
                    continue;
                const double w = (k & 1 ? fx : 1 - fx) * (k >> 1 ? fy : 1 - fy);
                float pixel[4];
                exact.getpixel(px, py, pixel);
                pixel[c] += float(w * it[c]);
                exact.setpixel(px, py, pixel);
            }
        }
    }
    const auto [cells, one] = bokeh_scores(stack, exact);
    WARN("fence under lateral aberration, against the thin lens: " << cells
         << " dB with cells, " << one << " dB with one cell");
    // One cell's score while lateral aberration took no cells.
    CHECK(cells >= 35.0);
    CHECK(one < cells - 5.0);
}

TEST_CASE("a light far beyond half's range keeps its fence's shadow, finite, in proportion")
{
    // The layers' changes are kept in half (largest 65504): a light a
    // billion times brighter came out infinite, and NaN where "over" met
    // it. Light adds up: the fence's every colour times a billion is the
    // same picture times a billion.
    auto fence_times = [](float k) {
        Stack stack;
        stack.add("light", 10.0f, [=](int x, int y, float* rgba) {
            const bool light = std::hypot(x + 0.5 - centre_x, y + 0.5 - centre_y) < 3.0;
            rgba[0] = rgba[1] = rgba[2] = k * (light ? 1.0f : 0.05f);
            rgba[3] = 1.0f;
        });
        stack.add("bars", 1.0f, [=](int x, int, float* rgba) {
            if ((x - centre_x + 256) % 16 < 4) {
                rgba[0] = rgba[1] = rgba[2] = k * 0.01f;
                rgba[3] = 1.0f;
            }
        });
        return stack.engine(0);
    };
    const ImageBuf once = fence_times(1.0f), bright = fence_times(1e9f);
    double worst = 0.0;
    for (int y = bokeh.ybegin; y < bokeh.yend; ++y)
        for (int x = bokeh.xbegin; x < bokeh.xend; ++x)
            for (int c = 0; c < 3; ++c) {
                const double a = once.getchannel(x, y, 0, c), b = bright.getchannel(x, y, 0, c);
                REQUIRE(std::isfinite(b));
                worst = std::max(worst, std::abs(b / 1e9 - a) / std::max(a, 1e-3));
            }
    INFO("most relative difference from the picture times a billion " << worst);
    CHECK(worst < 2e-3);
}

TEST_CASE("a fence before a row of lights wider than a window of cells is cut into none")
{
    // A data window 15 tiles wide with lights all along it: the cells are
    // spread in windows of at most 8 tiles, and the lights' bokeh crosses
    // from one window into the next.
    const ROI wide(60, 540, 160, 240, 0, 1, 0, 4);
    auto every_40_px = [&](int x, int y) {
        const double along = x + 0.5 - wide.xbegin;
        return std::hypot(along - 40.0 * std::round(along / 40.0), y + 0.5 - centre_y) < 3.0;
    };
    const Stack stack = fence([](int) { return true; }, every_40_px, Stack(0, wide));
    const ROI lights(wide.xbegin + 16, wide.xend - 16, centre_y - 12, centre_y + 12, 0, 1, 0, 4);
    const ImageBuf exact = thin_lens(stack.lens, lights);
    const double cells = psnr_over(stack.engine(0), exact, lights);
    WARN("fence before a row of lights, against the thin lens: " << cells << " dB with cells");
    CHECK(cells >= 35.0);
}

TEST_CASE("where every footprint through a cell is blocks wide, the cells are found over blocks")
{
    // Both layers far out of focus, in front of it: bars 8 px wide every 16
    // at 0.5 m (CoC 142 px) before a light at 0.8 m (78 px). Through each of
    // the 12 x 12 cells the light blurs by 6.5 px: blocks of 2 x 2 pixels.
    // A faint layer nearly in focus behind them (2.7 m, 1.6 px) binds the
    // cells to pixels, and changes the picture by a millionth.
    auto stack = [](bool faint) {
        Stack s;
        if (faint)
            s.add("faint", 2.7f, [](int, int, float* rgba) { rgba[3] = 1e-6f; });
        s.add("light", 0.8f, [](int x, int y, float* rgba) {
            const bool light = std::hypot(x + 0.5 - centre_x, y + 0.5 - centre_y) < 4.0;
            rgba[0] = rgba[1] = rgba[2] = light ? 1.0f : 0.05f;
            rgba[3] = 1.0f;
        });
        add_bars(s, 0.5f, 8);
        return s;
    };
    const Stack blurred = stack(false), bound = stack(true);
    const ROI light(centre_x - 40, centre_x + 40, centre_y - 40, centre_y + 40, 0, 1, 0, 4);
    const ImageBuf exact = thin_lens(blurred.lens, light, 96);
    SubApertureReport over_blocks, over_pixels;
    const ImageBuf blocks = blurred.engine(144, OutputWindow::Input, &over_blocks),
                   pixels = bound.engine(144, OutputWindow::Input, &over_pixels);
    const double by_blocks = psnr_over(blocks, exact, light),
                 by_pixels = psnr_over(pixels, exact, light),
                 one = psnr_over(blurred.engine(1), exact, light);
    WARN("blurred bars before a blurred light, against the thin lens: "
         << by_blocks << " dB over blocks, " << by_pixels << " dB over pixels, " << one
         << " dB with one cell; blocks against pixels " << psnr_over(blocks, pixels, light)
         << " dB");
    REQUIRE(over_blocks.tiles_with_cells > 0);
    CHECK(over_blocks.tiles_over_blocks == over_blocks.tiles_with_cells);
    CHECK(over_pixels.tiles_over_blocks == 0);
    CHECK(by_blocks >= by_pixels - 0.5);
    CHECK(psnr_over(blocks, pixels, light) >= 40.0);
    CHECK(one < by_blocks - 10.0);
}

TEST_CASE("a wide occluder takes the cells its whole width asks for, not its corner's in a tile")
{
    // A square 200 px wide at 0.5 m (CoC 142 px) before a checker at 10 m:
    // 5 cells across keep its footprint through each within a 32 px tile.
    // Its corners cover 8 x 8 pixels of their tiles, and those 8 pixel runs
    // asked for 9 across while widths were measured within a tile. A bar
    // the data window cuts to its last 3 rows asked for 12 across; it asks
    // for nothing more: the window ends there, not the bar.
    const ROI data(150, 450, 60, 340, 0, 1, 0, 4);
    Stack stack(0, data);
    stack.add("checker", 10.0f, [](int x, int y, float* rgba) {
        rgba[0] = rgba[1] = rgba[2] = ((x / 8 + y / 8) % 2) ? 0.8f : 0.1f;
        rgba[3] = 1.0f;
    });
    const ROI square(data.xbegin + 56, data.xbegin + 256, data.ybegin + 56, data.ybegin + 256);
    stack.add("square and bar", 0.5f, [&](int x, int y, float* rgba) {
        if (square.contains(x, y) || (y < data.ybegin + 3 && x >= 200 && x < 400)) {
            rgba[0] = rgba[1] = rgba[2] = 0.02f;
            rgba[3] = 1.0f;
        }
    });
    const ROI edge(square.xend - 32, square.xend + 32, centre_y - 32, centre_y + 32, 0, 1, 0, 4);
    const ImageBuf exact = thin_lens(stack.lens, edge);
    SubApertureReport report;
    const double cells = psnr_over(stack.engine(0, OutputWindow::Input, &report), exact, edge);
    const double one = psnr_over(stack.engine(1), exact, edge);
    WARN("wide square's edge over a checker, against the thin lens: " << cells << " dB with "
         << report.most_cells << " cells, " << one << " dB with one cell");
    CHECK(report.most_cells == 25);
    CHECK(cells >= one + 5.0);
}

TEST_CASE("a smooth gradient behind a fence takes no cells: every part of the lens sees it alike")
{
    // A wall at 10 m brightening by 1% across the frame behind the fence:
    // whatever part of the lens a pixel sees it through, it sees the same
    // light to within a thousandth.
    Stack stack;
    stack.add("gradient", 10.0f, [](int, int y, float* rgba) {
        rgba[0] = rgba[1] = rgba[2] = 0.5f + 0.005f * (y - frame.ybegin) / frame.height();
        rgba[3] = 1.0f;
    });
    add_bars(stack, 1.0f, 4);
    SubApertureReport report;
    const ImageBuf cells = stack.engine(0, OutputWindow::Input, &report);
    const ImageBuf exact = thin_lens(stack.lens, bokeh);
    WARN("a gradient behind a fence, against the thin lens: " << psnr_over(cells, exact, bokeh)
         << " dB with " << report.tiles_with_cells << " tiles of cells");
    CHECK(report.tiles_with_cells == 0);
    CHECK(psnr_over(cells, exact, bokeh) >= 50.0);
}

TEST_CASE("the fence's shadow runs on past the data window into a grown one")
{
    // The light at the right edge of the data and display windows: half its
    // bokeh lands in the margin that the grown window adds.
    const Stack stack = fence([](int) { return true; }, frame.xend - 2, frame.xend - 600);
    const ROI edge(frame.xend - 14, frame.xend + 12, centre_y - 12, centre_y + 12, 0, 1, 0, 4);
    const ROI margin(frame.xend, edge.xend, edge.ybegin, edge.yend, 0, 1, 0, 4);
    const ImageBuf exact = thin_lens(stack.lens, edge);
    const ImageBuf cells = stack.engine(0, OutputWindow::Grown),
                   one = stack.engine(1, OutputWindow::Grown);
    REQUIRE(cells.roi().contains(margin));
    const double in_margin = psnr_over(cells, exact, margin), one_there = psnr_over(one, exact, margin);
    WARN("fence past the data window, over the margin: " << in_margin << " dB with cells, "
         << one_there << " dB with one cell");
    CHECK(in_margin >= 35.0);
    CHECK(one_there < in_margin - 5.0);
}

TEST_CASE("a near bar cuts the far light's bokeh on the side the thin lens says")
{
    // One bar right of the light: the parts of the lens that see the bar in
    // front of the light are on one side, so it shades one side of the
    // bokeh; which one is the thin lens's answer. One cell shows only the
    // bar's blur, not its shadow.
    const Stack stack = fence([](int bar) { return bar == 1; });
    const ImageBuf exact = thin_lens(stack.lens, bokeh);
    auto sides = [&](const ImageBuf& image) {
        double left = 0.0, right = 0.0;
        for (int y = bokeh.ybegin; y < bokeh.yend; ++y)
            for (int x = bokeh.xbegin; x < bokeh.xend; ++x) {
                float p[4];
                image.getpixel(x, y, p);
                (x < centre_x ? left : right) += p[1];
            }
        return right / left;
    };
    const double truth = sides(exact), cells = sides(stack.engine(0)),
                 one = sides(stack.engine(1));
    INFO("right over left: thin lens " << truth << ", cells " << cells << ", one cell " << one);
    REQUIRE(std::abs(truth - 1.0) > 0.05);
    CHECK((cells - 1.0) * (truth - 1.0) > 0.0);
    CHECK(std::abs(cells - truth) < 0.3 * std::abs(truth - 1.0));
    CHECK(std::abs(one - truth) > std::abs(cells - truth));
}

TEST_CASE("a blurred opaque edge over sharp stripes is what the thin lens sees")
{
    Stack stack;
    // Stripes in focus (3 m), an opaque edge at 1.25 m: its CoC is 40 px.
    stack.add("stripes", 3.0f, [](int x, int, float* rgba) {
        rgba[0] = rgba[1] = rgba[2] = (x / 3) % 2 ? 1.0f : 0.05f;
        rgba[3] = 1.0f;
    });
    stack.add("edge", 1.25f, [](int x, int, float* rgba) {
        if (x < centre_x) {
            rgba[0] = 0.3f;
            rgba[1] = 0.2f;
            rgba[2] = 0.1f;
            rgba[3] = 1.0f;
        }
    });
    const ROI band(centre_x - 20, centre_x + 20, centre_y - 20, centre_y + 20, 0, 1, 0, 4);
    const ImageBuf exact = thin_lens(stack.lens, band);
    const double cells = psnr_over(stack.engine(0), exact, band);
    WARN("blurred edge over stripes, against the thin lens: " << cells << " dB");
    CHECK(cells >= 35.0);
}

TEST_CASE("depth as a data channel is composited per part of the lens as colour is")
{
    // A light at 10 m before a wall at 60 m, behind a fence at 1 m: the
    // light's bokeh mixes their depths and the bars' in the proportions each
    // part of the lens sees. Depth times alpha, spread as colour and over
    // alpha, is what the thin lens sees of depth.
    Stack stack, depth_as_colour;
    std::vector<LensLayer> depths;
    auto add = [&](const char* name, float depth, const Shade& shade) {
        stack.add(name, depth, shade);
        depth_as_colour.add(name, depth, [&](int x, int y, float* rgba) {
            shade(x, y, rgba);
            rgba[0] = rgba[1] = rgba[2] = depth * rgba[3];
        });
        depths.push_back(depth_as_colour.lens.back());
    };
    add("wall", 60.0f, [](int, int, float* rgba) {
        rgba[0] = rgba[1] = rgba[2] = 0.05f;
        rgba[3] = 1.0f;
    });
    add("light", 10.0f, [](int x, int y, float* rgba) {
        if (std::hypot(x + 0.5 - centre_x, y + 0.5 - centre_y) < 3.0)
            rgba[0] = rgba[1] = rgba[2] = rgba[3] = 1.0f;
    });
    add("bars", 1.0f, [](int x, int, float* rgba) {
        if ((x - centre_x + 8 + 1600) % 16 >= 6 && (x - centre_x + 8 + 1600) % 16 < 10) {
            rgba[0] = rgba[1] = rgba[2] = 0.01f;
            rgba[3] = 1.0f;
        }
    });
    const ImageBuf exact = thin_lens(depths, bokeh);
    // The mean distance in metres from the thin lens's depth over the
    // bokeh, and the farthest from the depth spread as colour.
    auto depth_error = [&](int cells, double& from_colour) {
        SpreadOptions spread;
        spread.aperture_cells = cells;
        DataPlan plan;
        plan.depth = true;
        ImageBuf data;
        REQUIRE(data_channels(data, stack.engine(cells), stack.scene, lens_camera(), spread,
                              ApertureImages(), OutputWindow::Input, plan));
        const ImageBuf colour = depth_as_colour.engine(cells);
        double error = 0.0;
        from_colour = 0.0;
        for (int y = bokeh.ybegin; y < bokeh.yend; ++y)
            for (int x = bokeh.xbegin; x < bokeh.xend; ++x) {
                float truth[4], spread_depth[4], z[2];
                exact.getpixel(x, y, truth);
                colour.getpixel(x, y, spread_depth);
                data.getpixel(x, y, z);
                error += std::abs(z[0] - truth[0] / truth[3]);
                from_colour = std::max(from_colour,
                                       double(std::abs(z[0] - spread_depth[0] / spread_depth[3])));
            }
        return error / double(bokeh.npixels());
    };
    double cells_from_colour, one_from_colour;
    const double cells = depth_error(0, cells_from_colour), one = depth_error(1, one_from_colour);
    WARN("depth through the fence, mean error against the thin lens: " << cells
         << " m with cells, " << one << " m with one cell");
    CHECK(cells_from_colour < 1e-3);
    CHECK(one_from_colour < 1e-3);
    CHECK(cells < 0.7 * one);
}

TEST_CASE("lights behind a sloping opaque wall stay hidden through every part of the lens")
{
    // A wall sloping across the frame and down it, before lights at 10 m,
    // behind a fence at 1 m that makes the tiles take cells. Its radius
    // changes along every row and column; no part of the lens sees past
    // it, so lights 400 times brighter must change nothing there. The wall
    // far out of focus (2 to 2.6 m), and nearly in focus (2.6 to 3 m: its
    // footprints through a cell are narrower than a pixel).
    const float near = GENERATE(2.0f, 2.6f);
    const ROI data(150, 450, 60, 340, 0, 1, 0, 4);
    auto scene = [&](float light) {
        Stack stack(0, data);
        stack.add("lights", 10.0f, [=](int x, int y, float* rgba) {
            const bool lit = (x % 12 < 3) && (y % 12 < 3);
            rgba[0] = rgba[1] = rgba[2] = lit ? light : 0.05f;
            rgba[3] = 1.0f;
        });
        const float slope = 0.5f * (3.0f - near) / 2.0f;
        stack.add("wall",
                  [&](int x, int y) {
                      return near + slope * float(x - data.xbegin) / float(data.width())
                             + slope * float(y - data.ybegin) / float(data.height());
                  },
                  [](int x, int y, float* rgba) {
                      rgba[0] = 0.2f + 0.1f * float((x / 5 + y / 7) % 3);
                      rgba[1] = rgba[2] = 0.2f;
                      rgba[3] = 1.0f;
                  });
        add_bars(stack, 1.0f, 4);
        return stack;
    };
    const Stack dark = scene(0.05f), bright = scene(20.0f);
    // Away from the data window's edges, where the lens sees round the wall.
    const ROI inside(data.xbegin + 40, data.xend - 40, data.ybegin + 40, data.yend - 40, 0, 1, 0, 4);
    auto through = [&](int cells) {
        using namespace OIIO::ImageBufAlgo;
        const PixelStats stats = computePixelStats(
            absdiff(bright.engine(cells), dark.engine(cells), inside), inside);
        return double(*std::max_element(stats.max.begin(), stats.max.begin() + 3));
    };
    const double cells = through(0), one = through(1);
    WARN("lights 400 times brighter behind a wall from " << near << " m, most let through: "
         << cells << " with cells, " << one << " with one cell");
    CHECK(cells <= one + 1e-4);
}
