// Speed of the spreading filters, in ms per megapixel per layer.
//
// The box filter runs on a 4096x2160 layer at radius 1, 8, 64 and 256; its
// time should not depend on the radius. Scanline spreading (disc at radius
// 8, 32 and 128, hexagon at 32) costs the footprint's height per pixel;
// tent and smooth are constant time again. The direct reference is O(r²) per
// pixel, so it runs on a 512x270 crop: per-megapixel figures compare.
#include <benchmark/benchmark.h>

#include <OpenImageIO/imagebufalgo.h>

#include <defocus/layered_dof.h>
#include <defocus/spread.h>

using namespace OIIO;

namespace {

struct Layer {
    ImageBuf color, radius;
};

Layer make_layer(int width, int height, float coc_radius)
{
    Layer layer { ImageBuf(ImageSpec(width, height, 4, TypeFloat)),
                  ImageBuf(ImageSpec(width, height, 1, TypeFloat)) };
    ImageBufAlgo::noise(layer.color, "uniform", 0.01f, 10.0f, false, 1);
    ImageBufAlgo::fill(layer.radius, { coc_radius });
    return layer;
}

void report(benchmark::State& state, const Layer& layer)
{
    const double megapixels = layer.color.spec().image_pixels() * 1e-6;
    state.counters["ms_per_MP"] = benchmark::Counter(
        megapixels * 1e-3,
        benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

/// Times spread(out, layer) on a width x height layer of the benchmark's
/// radius.
template<typename Spread>
void measure(benchmark::State& state, int width, int height, Spread&& spread)
{
    const Layer layer = make_layer(width, height, float(state.range(0)));
    for (auto _ : state) {
        ImageBuf out;
        spread(out, layer);
        benchmark::DoNotOptimize(out.localpixels());
    }
    report(state, layer);
}

void BM_box(benchmark::State& state)
{
    measure(state, 4096, 2160, [](ImageBuf& out, const Layer& l) {
        defocus::spread_box(out, l.color, l.radius);
    });
}

/// Scanline spreading of an aperture on the same 4096x2160 layer.
void scanline(benchmark::State& state, const defocus::Aperture& aperture)
{
    const defocus::ApertureProfile profile(aperture);
    measure(state, 4096, 2160, [&](ImageBuf& out, const Layer& l) {
        defocus::spread_scanline(out, l.color, l.radius, profile);
    });
}

void BM_disc(benchmark::State& state)
{
    scanline(state, defocus::Aperture());
}

void BM_polygon(benchmark::State& state)
{
    defocus::Aperture hexagon;
    hexagon.shape = defocus::ApertureShape::Polygon;
    scanline(state, hexagon);
}

/// Tent (order 2) and smooth (order 3) by repeated integration.
void smooth(benchmark::State& state, int order)
{
    measure(state, 4096, 2160, [order](ImageBuf& out, const Layer& l) {
        defocus::spread_smooth(out, l.color, l.radius, order);
    });
}

void BM_tent(benchmark::State& state)
{
    smooth(state, 2);
}

void BM_smooth(benchmark::State& state)
{
    smooth(state, 3);
}

/// The hybrid method on the same layer: box for most pixels, a disc PSF
/// image for one highlight in 1000.
void BM_hybrid_box(benchmark::State& state)
{
    Layer layer = make_layer(4096, 2160, float(state.range(0)));
    for (int i = 0; i < 4096 * 2160 / 1000; ++i) {
        const float highlight[4] = { 500.0f, 500.0f, 500.0f, 1.0f };
        layer.color.setpixel((i * 7919) % 4096, (i * 104729) % 2160, highlight);
    }
    const std::string dir = EXAMPLES_DIR;
    auto psf = std::make_shared<defocus::PsfImage>();
    std::string error;
    if (!psf->load(dir + "/psf/disc_rim.exr", error)) {
        state.SkipWithError(error.c_str());
        return;
    }
    defocus::Scene scene;
    scene.spec = layer.color.spec();
    defocus::Layer l { "layer", layer.color, ImageBuf(ImageSpec(4096, 2160, 1, TypeFloat)) };
    l.color.specmod().alpha_channel = 3;
    scene.layers.push_back(l);
    // Depth that gives the benchmark's radius with focus at 1 m.
    defocus::RenderSettings settings;
    settings.camera.focus_distance = 1.0;
    settings.aperture.shape = defocus::ApertureShape::Box;
    settings.psf_image = psf;
    const defocus::CircleOfConfusion coc(settings.camera, 4096);
    ImageBufAlgo::fill(scene.layers[0].depth, { float(coc.depth_at(2.0 * state.range(0))) });
    for (auto _ : state) {
        ImageBuf out;
        defocus::render_layered_dof(out, scene, settings);
        benchmark::DoNotOptimize(out.localpixels());
    }
    report(state, layer);
}

void BM_direct(benchmark::State& state)
{
    measure(state, 512, 270, [](ImageBuf& out, const Layer& l) {
        defocus::spread_direct(out, l.color, l.radius, defocus::box_footprint);
    });
}

}  // namespace

BENCHMARK(BM_box)->Arg(1)->Arg(8)->Arg(32)->Arg(64)->Arg(256)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_disc)->Arg(8)->Arg(32)->Arg(128)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_polygon)->Arg(32)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_tent)->Arg(8)->Arg(64)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_smooth)->Arg(8)->Arg(64)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_hybrid_box)->Arg(32)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_direct)->Arg(8)->Arg(32)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_MAIN();
