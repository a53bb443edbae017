#include <defocus/composite/defocus_layers.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/parallel.h>
#include <OpenImageIO/timer.h>

#include <defocus/composite/holdout.h>
#include <defocus/layers/edges.h>

#include "composite/frame_spreads.h"
#include "composite/over_rows.h"
#include "composite/sub_aperture.h"
#include "spread/spread_engine.h"
#include "spread/spread_plan.h"
#include "util/float_pixels.h"
#include "util/fresh_image.h"
#include "util/parallel_rows.h"
#include "util/simd.h"

namespace defocus {

using namespace OIIO;

bool coc_radius(ImageBuf& dst, const ImageBuf& depth,
                const CircleOfConfusion& coc, ROI roi, int nthreads, CocChannel channel)
{
    if (!roi.defined())
        roi = depth.roi();
    roi.chbegin = 0;
    roi.chend = 1;
    ImageSpec spec(roi, TypeFloat);
    spec.channelnames = { "radius" };
    reset_for_overwrite(dst, spec, nthreads);
    const FloatPixels z(depth, roi);
    // Depth is mostly one channel: a loop of unit stride vectorises.
    auto rows = [&](auto stride) {
        parallel_for(roi.ybegin, roi.yend, [&](int y) {
            const float* in = z(roi.xbegin, y);
            float* out = static_cast<float*>(dst.pixeladdr(roi.xbegin, y));
            for (int x = 0; x < roi.width(); ++x)
                out[x] = float(
                    0.5 * std::abs(coc.diameter(in[x * stride], roi.xbegin + x, y, channel)));
        }, by_rows(nthreads));
    };
    if (z.nchannels() == 1)
        rows(std::integral_constant<int, 1>());
    else
        rows(z.nchannels());
    return true;
}

namespace {

/// Where a magnified pass's light can come from: the window, grown by the
/// largest displacement lateral aberration gives within it, as far as
/// anything is lit.
ROI magnified_reach(const ROI& window, const ROI& grown, const Imath::V2d& centre,
                    double lateral_ca)
{
    const double farthest = std::max({ std::abs(window.xbegin - centre.x),
                                       std::abs(window.xend - centre.x),
                                       std::abs(window.ybegin - centre.y),
                                       std::abs(window.yend - centre.y) });
    const double lateral = std::abs(lateral_ca);
    const int margin = int(std::ceil(lateral * farthest / (1.0 - lateral))) + 2;
    const ROI reach(window.xbegin - margin, window.xend + margin, window.ybegin - margin,
                    window.yend + margin, 0, 1, 0, 4);
    return roi_intersection(reach, roi_union(grown, window));
}

/// The depth that stands for layer `i` of `scene` against a holdout: the
/// depth of its alpha-weighted mean inverse depth, which orders the layers;
/// 0 past the front-most layer.
double layer_depth(const LayeredScene& scene, size_t i)
{
    if (i >= scene.reports.size())
        return 0.0;
    const double inverse = scene.reports[i].mean_inverse_depth;
    return inverse > 0.0 ? 1.0 / inverse : INFINITY;
}

/// The layers' changes from compositing per cell of the aperture, for each
/// CoC a pass takes (CocChannel): under axial chromatic aberration red and
/// blue are composited on their own spread alpha, and so are their cells.
struct ChannelCells {
    SubApertureLayers green, red_blue;

    SubApertureLayers& of(CocChannel coc) { return coc == CocChannel::RedBlue ? red_blue : green; }
    const SubApertureLayers& of(CocChannel coc) const
    {
        return coc == CocChannel::RedBlue ? red_blue : green;
    }
};

/// Composites one pass of a layer into the frame over `window`: as the
/// engine spreads it (stored, `onto_black`, for the back-most layer), or
/// from its spread image; a magnified pass from an image of its spread over
/// `reach` (light from just outside the window lands inside it).
void composite_pass(ImageBuf& frame, LayerPass& p, bool onto_black, const ImageSpec& scene,
                    const ROI& window, const ROI& reach, double lateral_ca,
                    const Imath::V2d& centre, const ChannelCells& channel_cells, size_t layer,
                    int nthreads)
{
    const SubApertureLayers& cells = channel_cells.of(p.channels.coc);
    if (p.channels.magnified) {
        const ChannelPass& c = p.channels;
        const bool direct = c.alpha || c.colour[0] || c.colour[1] || c.colour[2];
        // The layer's changes go into its spread, which the magnified
        // channels are composited from: then the direct ones are composited
        // from it too, after.
        const bool changed = cells.changes(layer);
        if (p.spread.rows) {
            // Kept where it lights anything: the rest is nothing to composite.
            ROI lit = roi_intersection(reach, p.spread.rows->extent());
            lit.chbegin = 0;
            lit.chend = 4;
            if (lit.npixels() <= 0)
                return;
            reset_zeroed(p.spread.apart, result_spec(scene, lit, TypeFloat), nthreads);
            Keep keep(p.spread.apart);
            KeepAndOver keep_and_over(p.spread.apart, frame, c);
            p.spread.rows->run(lit,
                               direct && !changed ? static_cast<RowSink&>(keep_and_over) : keep,
                               nthreads);
        }
        if (changed)
            add_changes(p.spread.apart, cells, layer, nthreads);
        if (direct && (changed || !p.spread.rows))
            composite_image(frame, p.spread.apart, c, nullptr, layer, nthreads);
        composite_magnified(frame, p.spread.apart, 0, 1.0 + lateral_ca, centre, nthreads);
        composite_magnified(frame, p.spread.apart, 2, 1.0 - lateral_ca, centre, nthreads);
    } else if (p.spread.rows) {
        Over over(frame, p.channels, onto_black, &cells, layer);
        p.spread.rows->run(window, over, nthreads);
    } else if (p.spread.apart.initialized()) {
        composite_image(frame, p.spread.apart, p.channels, &cells, layer, nthreads);
    }
}

/// The part of `window` a layer's spreads light (all of it, magnified);
/// empty when it has none.
ROI lit_window(const LayerSpreads& layer, const ROI& window)
{
    ROI lit;
    bool magnified = false;
    for (const LayerPass& p : layer.passes) {
        lit = roi_union(lit, p.spread.extent());
        magnified |= p.channels.magnified;
    }
    lit = magnified ? window : roi_intersection(window, lit);
    lit.chbegin = 0;
    lit.chend = 4;
    return layer.passes.empty() || lit.npixels() <= 0 ? ROI(0, 0, 0, 0, 0, 1, 0, 4) : lit;
}

/// Composites the layers' passes into the frame over `window`, back to
/// front, each layer's spreads set up when it comes and freed once
/// composited, and cuts what is composited by the holdout in front of each
/// layer up to the next. False with `error`.
bool composite_layers(ImageBuf& frame, const LayeredScene& scene, FrameSpreads& layers,
                      const ChannelCells& cells, size_t back, const ROI& window, const ROI& reach,
                      double lateral_ca, const Imath::V2d& centre, std::string& error,
                      int nthreads)
{
    bool composited = false;
    for (size_t i = 0; i < layers.size(); ++i) {
        if (!layers.set_up(i, error))
            return false;
        const LayerPass* onto_black = i == back ? storable_pass(layers[i]) : nullptr;
        // A layer's passes write different channels of the frame, so their
        // order does not matter.
        for (LayerPass& p : layers[i].passes)
            composite_pass(frame, p, &p == onto_black, scene.spec, window, reach, lateral_ca,
                           centre, cells, i, nthreads);
        // Until the back-most layer lands, the frame is not set.
        composited |= !layers[i].passes.empty();
        if (composited && scene.holdout)
            hold_out(frame, *scene.holdout, layer_depth(scene, i + 1), layer_depth(scene, i),
                     window, nthreads);
        layers.release(i);
    }
    return true;
}

/// Composites each layer's passes onto a black frame of its own over the
/// part of `window` it lights, back to front, and hands it to `sink`, each
/// layer's spreads freed once composited.
bool composite_apart(const LayeredScene& scene, FrameSpreads& layers,
                     const ChannelCells& cells,
                     const ROI& window, const ROI& reach,
                     double lateral_ca, const Imath::V2d& centre, const LayerSink& sink,
                     int nthreads)
{
    // One buffer, as large as the largest layer's frame, holds each in
    // turn: a fresh one per layer faulted in a 4K frame's pages again.
    size_t largest = 0;
    for (size_t i = 0; i < layers.size(); ++i)
        largest = std::max(largest, size_t(lit_window(layers[i], window).npixels()));
    std::unique_ptr<float[]> pixels(new float[4 * largest]);
    for (size_t i = 0; i < scene.layers.size(); ++i) {
        const ROI lit = lit_window(layers[i], window);
        if (lit.npixels() <= 0)
            continue;
        const LayerPass* alone = storable_pass(layers[i]);
        ImageBuf frame(result_spec(scene.spec, lit, TypeFloat), pixels.get());
        zero_except(frame, alone ? alone->spread.rows->extent() : ROI(), nthreads);
        for (LayerPass& p : layers[i].passes)
            composite_pass(frame, p, &p == alone, scene.spec, lit, reach, lateral_ca, centre,
                           cells, i, nthreads);
        layers.release(i);
        if (!sink(i, frame, window))
            return false;
    }
    return true;
}

/// The layers' changes from compositing per cell of the aperture for each
/// CoC the camera's passes take, with the aperture's shape (a disc,
/// polygon, mask or box; the soft PSFs of tent and smooth take none) as the
/// barrel clips it (a cat's eye), over the frame's window: the display or
/// data window, or both grown to wherever the layers' light lands.
void compute_cells(ChannelCells& cells, const LayeredScene& scene, const Camera& camera,
                   const SpreadOptions& spread, const SpreadPlan& plan, OutputWindow window,
                   const ROI& display, int nthreads)
{
    std::shared_ptr<const RowProfile> shape
        = plan.profile ? plan.profile
          : spread.aperture.shape == ApertureShape::Box ? std::make_shared<BoxProfile>(plan.aspect)
                                                         : nullptr;
    if (!shape || !takes_aperture_cells(spread, scene))
        return;
    const CircleOfConfusion coc(camera, scene.spec.roi_full());
    const ROI where = window == OutputWindow::Display ? display
                      : window == OutputWindow::Input ? scene.spec.roi()
                                                      : roi_union(display, scene.spec.roi());
    for (const ChannelPass& pass : channel_passes(camera))
        cells.of(pass.coc).compute(scene, coc, pass.coc, shape, plan.cateye,
                                   spread.aperture_cells, where, window == OutputWindow::Grown,
                                   nthreads);
}

/// defocus_layers(), or with `apart` spread_layers_apart().
bool spread_and_composite(ImageBuf& dst, const LayeredScene& scene, const Camera& camera,
                          const SpreadOptions& spread, const ApertureImages& images,
                          OutputWindow output_window, std::vector<LayerReport>* report,
                          SpreadStats& stats, const LayerSink* apart,
                          std::vector<Layer>* freeing, int nthreads)
{
    Timer spread_timer;
    const ROI display(scene.spec.full_x, scene.spec.full_x + scene.spec.full_width,
                      scene.spec.full_y, scene.spec.full_y + scene.spec.full_height, 0, 1, 0, 4);
    SpreadPlan plan;
    std::string error;
    if (!plan_spread(spread, images, camera, display, scene.reports, scene.luma, plan, error)) {
        dst.errorfmt("{}", error);
        return false;
    }
    const Imath::V2d centre = plan.cateye.centre;
    const bool magnified = camera.lateral_ca != 0.0;
    // The cells are made from the layers before they are spread, and
    // perhaps freed.
    ChannelCells cells;
    compute_cells(cells, scene, camera, spread, plan, output_window, display, nthreads);
    stats.cells = cells.green.report();
    FrameSpreads layers(scene, camera, plan, freeing, nthreads);

    // The frame's window, and where magnified light comes from, depend on
    // how far the layers' spreads light: then every layer is set up first.
    const bool extents_first = output_window == OutputWindow::Grown || magnified || apart;
    ROI grown = display;
    if (extents_first) {
        if (!layers.set_up_all(error)) {
            dst.errorfmt("{}", error);
            return false;
        }
        for (size_t i = 0; i < layers.size(); ++i)
            for (const LayerPass& p : layers[i].passes)
                grown = roi_union(grown, p.spread.extent());
    }
    ROI window = output_window == OutputWindow::Display ? display
                 : output_window == OutputWindow::Grown ? grown
                                                          : scene.spec.roi();
    window.chbegin = 0;
    window.chend = 4;
    const ImageSpec frame_spec = result_spec(scene.spec, window, TypeFloat);
    const ROI reach = magnified_reach(window, grown, centre, camera.lateral_ca);
    if (apart) {
        const bool done = composite_apart(scene, layers, cells, window, reach,
                                          camera.lateral_ca, centre, *apart, nthreads);
        if (report)
            report->insert(report->end(), layers.reports.begin(), layers.reports.end());
        stats.spread += spread_timer();
        return done;
    }
    // The back-most layer is stored onto the frame rather than composited,
    // so only the frame beyond its reach is cleared first.
    size_t back = 0;
    if (!layers.set_up_back(back, error)) {
        dst.errorfmt("{}", error);
        return false;
    }
    const LayerPass* stored = back < layers.size() ? storable_pass(layers[back]) : nullptr;
    // dst's pixels, when it has them in the frame's layout, are reused
    // (swapped, not moved: dst stays valid for an error).
    ImageBuf frame;
    if (holds_pixels_like(dst, frame_spec))
        frame.swap(dst);
    reset_zeroed_except(frame, frame_spec, stored ? stored->spread.rows->extent() : ROI(),
                        nthreads);
    if (!composite_layers(frame, scene, layers, cells, back, window, reach, camera.lateral_ca,
                          centre, error, nthreads)) {
        dst.errorfmt("{}", error);
        return false;
    }
    if (report)
        report->insert(report->end(), layers.reports.begin(), layers.reports.end());
    stats.spread += spread_timer();
    dst = std::move(frame);
    return true;
}

}  // namespace

ReachOnly reach_only(const Camera& camera, const SpreadOptions& spread,
                     const ApertureImages& images)
{
    ReachOnly reach { camera, spread, { images.mask, nullptr } };
    reach.camera.axial_ca = reach.camera.lateral_ca = 0.0;
    reach.spread.psf_image.clear();
    return reach;
}

ImageSpec result_spec(const ImageSpec& scene, const ROI& window, TypeDesc format)
{
    ImageSpec spec(window, format);
    spec.nchannels = 4;
    spec.channelnames = { "R", "G", "B", "A" };
    spec.alpha_channel = 3;
    spec.full_x = scene.full_x;
    spec.full_y = scene.full_y;
    spec.full_width = scene.full_width;
    spec.full_height = scene.full_height;
    return spec;
}

namespace {

/// spread_and_composite(), with running out of memory reported in `dst`.
bool spread_guarded(ImageBuf& dst, const LayeredScene& scene, const Camera& camera,
                    const SpreadOptions& spread, const ApertureImages& images,
                    OutputWindow window, std::vector<LayerReport>* report,
                    SpreadStats* stats, const LayerSink* apart, std::vector<Layer>* freeing,
                    int nthreads)
{
    SpreadStats unused;
    // Errors are reported, never thrown through the API; running out of
    // memory on a huge blur is the one exception the filters can raise.
    try {
        return spread_and_composite(dst, scene, camera, spread, images, window, report,
                                    stats ? *stats : unused, apart, freeing, nthreads);
    } catch (const std::bad_alloc&) {
        dst.errorfmt("out of memory (the layers and the blur are too large)");
        return false;
    }
}

}  // namespace

bool defocus_layers(ImageBuf& dst, const LayeredScene& scene, const Camera& camera,
                    const SpreadOptions& spread, const ApertureImages& images,
                    OutputWindow window, std::vector<LayerReport>* report,
                    SpreadStats* stats, int nthreads)
{
    return spread_guarded(dst, scene, camera, spread, images, window, report, stats, nullptr,
                          nullptr, nthreads);
}

bool defocus_layers_freeing(ImageBuf& dst, LayeredScene& scene, const Camera& camera,
                            const SpreadOptions& spread, const ApertureImages& images,
                            OutputWindow window, std::vector<LayerReport>* report,
                            SpreadStats* stats, int nthreads)
{
    return spread_guarded(dst, scene, camera, spread, images, window, report, stats, nullptr,
                          &scene.layers, nthreads);
}

namespace {

/// spread_layers_apart(), freeing `freeing` (the scene's layers) when given.
bool spread_apart(const LayeredScene& scene, const Camera& camera, const SpreadOptions& spread,
                  const ApertureImages& images, OutputWindow window, const LayerSink& sink,
                  std::string& error, std::vector<LayerReport>* report, SpreadStats* stats,
                  std::vector<Layer>* freeing, int nthreads)
{
    ImageBuf errors;
    if (spread_guarded(errors, scene, camera, spread, images, window, report, stats, &sink,
                       freeing, nthreads))
        return true;
    if (errors.has_error())
        error = errors.geterror();
    return false;
}

}  // namespace

bool spread_layers_apart(const LayeredScene& scene, const Camera& camera,
                         const SpreadOptions& spread, const ApertureImages& images,
                         OutputWindow window, const LayerSink& sink, std::string& error,
                         std::vector<LayerReport>* report, SpreadStats* stats,
                         int nthreads)
{
    return spread_apart(scene, camera, spread, images, window, sink, error, report, stats,
                        nullptr, nthreads);
}

bool spread_layers_apart_freeing(LayeredScene& scene, const Camera& camera,
                                 const SpreadOptions& spread, const ApertureImages& images,
                                 OutputWindow window, const LayerSink& sink,
                                 std::string& error, std::vector<LayerReport>* report,
                                 SpreadStats* stats, int nthreads)
{
    return spread_apart(scene, camera, spread, images, window, sink, error, report, stats,
                        &scene.layers, nthreads);
}

bool largest_grown_window(ROI& window, const ImageSpec& scene, const Camera& camera,
                          const SpreadOptions& spread, const ApertureImages& images,
                          std::string& error, int nthreads)
{
    const ROI data = scene.roi();
    // Blocks of up to 32 pixels align to the pixel grid: a probe of that
    // size at each corner meets the same alignment as the data window.
    constexpr int probe = 64;
    // The largest blur is the camera's clamp wherever the lens focuses: the
    // probe takes a plain plane of focus, and a depth in front of it with
    // more blur than the camera allows.
    Camera plain = camera;
    plain.tilt_deg[0] = plain.tilt_deg[1] = 0.0;
    plain.split = SplitDiopter();
    plain.cateye = 0.0;          // clipped bokeh lies within the unclipped
    plain.in_focus_range = 0.0;  // a range only takes blur away
    const CircleOfConfusion coc(plain, scene.roi_full());
    const float depth = float(coc.depth_at(-4.0 * camera.max_blur_px - 4.0, 0, 0));
    window = data;
    for (const bool far_corner : { false, true }) {
        const int x0 = far_corner ? data.xend - probe : data.xbegin;
        const int y0 = far_corner ? data.yend - probe : data.ybegin;
        const ROI square(x0, x0 + probe, y0, y0 + probe, 0, 1, 0, 4);
        LayeredScene layered;
        // The scene's display window (the CoC scales with its width), the
        // square for data window.
        layered.spec = result_spec(scene, square, TypeFloat);
        ImageSpec depth_spec = layered.spec;
        depth_spec.nchannels = 1;
        depth_spec.channelnames = { "Z" };
        depth_spec.alpha_channel = -1;
        Layer layer { "probe", ImageBuf(layered.spec), ImageBuf(depth_spec) };
        ImageBufAlgo::fill(layer.color, { 1.0f, 1.0f, 1.0f, 1.0f });
        ImageBufAlgo::fill(layer.depth, { depth });
        layered.layers.push_back(std::move(layer));
        order_layers(layered, coc, nthreads);
        extend_edges(layered, coc, EdgeMode::Extend, nthreads);
        ImageBuf spread_probe;
        if (!defocus_layers(spread_probe, layered, plain, spread, images, OutputWindow::Grown,
                            nullptr, nullptr, nthreads)) {
            error = spread_probe.geterror();
            return false;
        }
        // The square shares the data window's corner, so what it lights
        // past that corner is what the frame's layers can light.
        const ROI lit = spread_probe.roi();
        if (far_corner) {
            window.xend = std::max(window.xend, lit.xend);
            window.yend = std::max(window.yend, lit.yend);
        } else {
            window.xbegin = std::min(window.xbegin, lit.xbegin);
            window.ybegin = std::min(window.ybegin, lit.ybegin);
        }
    }
    return true;
}

}  // namespace defocus

