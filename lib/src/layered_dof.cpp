#include <defocus/layered_dof.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <new>
#include <numeric>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/parallel.h>
#include <OpenImageIO/timer.h>

#include <defocus/spread.h>

namespace defocus {

using namespace OIIO;

bool coc_radius(ImageBuf& dst, const ImageBuf& depth,
                const CircleOfConfusion& coc, ROI roi, int nthreads)
{
    if (!roi.defined())
        roi = depth.roi();
    ImageSpec spec(roi, TypeFloat);
    spec.nchannels = 1;
    spec.channelnames = { "radius" };
    dst.reset(spec);
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const float z = *static_cast<const float*>(depth.pixeladdr(x, y));
            *static_cast<float*>(dst.pixeladdr(x, y)) = float(coc.radius(z));
        }
    }, paropt(nthreads));
    return true;
}

namespace {

/// Per-row partial sums of describe_layer(), reduced after the parallel pass.
struct RowDepth {
    int64_t pixels = 0;
    double zmin = INFINITY, zmax = -INFINITY;
    double weight = 0, weighted_inverse = 0;
};

}  // namespace

LayerReport describe_layer(const Layer& layer, const CircleOfConfusion& coc, int nthreads)
{
    const ROI roi = layer.color.roi();
    std::vector<RowDepth> rows(roi.height());
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        RowDepth& r = rows[y - roi.ybegin];
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const float a = static_cast<const float*>(layer.color.pixeladdr(x, y))[3];
            if (a <= 0.0f)
                continue;
            const double z = *static_cast<const float*>(layer.depth.pixeladdr(x, y));
            ++r.pixels;
            r.zmin = std::min(r.zmin, z);
            r.zmax = std::max(r.zmax, z);
            r.weight += a;
            r.weighted_inverse += a * (std::isinf(z) ? 0.0 : 1.0 / z);
        }
    }, paropt(nthreads));
    RowDepth total;
    for (const RowDepth& r : rows) {
        total.pixels += r.pixels;
        total.zmin = std::min(total.zmin, r.zmin);
        total.zmax = std::max(total.zmax, r.zmax);
        total.weight += r.weight;
        total.weighted_inverse += r.weighted_inverse;
    }
    LayerReport rep;
    rep.mean_inverse_depth = total.weight > 0 ? total.weighted_inverse / total.weight : 0.0;
    rep.name = layer.name;
    rep.pixels = total.pixels;
    rep.depth_min = total.pixels ? total.zmin : 0.0;
    rep.depth_max = total.pixels ? total.zmax : 0.0;
    rep.coc_min = total.pixels ? coc.diameter(rep.depth_min) : 0.0;
    rep.coc_max = total.pixels ? coc.diameter(rep.depth_max) : 0.0;
    return rep;
}

namespace {

/// One layer through the aperture's fast filter, or through the hybrid
/// method when a PSF image is set.
bool spread_layer(ImageBuf& dst, const ImageBuf& color, const ImageBuf& radius,
                  const RenderSettings& settings, const RowProfile* profile,
                  int64_t& psf_pixels, int nthreads)
{
    auto fast = [&](ImageBuf& out, const ImageBuf& in) {
        switch (settings.aperture.shape) {
        case ApertureShape::Box: return spread_box(out, in, radius, {}, nthreads);
        case ApertureShape::Tent: return spread_smooth(out, in, radius, 2, {}, nthreads);
        case ApertureShape::Smooth: return spread_smooth(out, in, radius, 3, {}, nthreads);
        default: return spread_aperture(out, in, radius, *profile, exact_highlight_threshold, {}, nthreads);
        }
    };
    if (!settings.psf_image)
        return fast(dst, color);

    const std::vector<uint8_t> slow = visible_bokeh(color, radius, settings.hybrid_threshold,
                                                    nthreads);
    psf_pixels = std::count(slow.begin(), slow.end(), uint8_t(1));
    // Split the layer: the selected pixels go one way, the rest the other.
    ImageBuf fast_part(color.spec()), slow_part(color.spec());
    const ROI roi = color.roi();
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const bool is_slow = slow[size_t(y - roi.ybegin) * roi.width() + (x - roi.xbegin)];
            const float* c = static_cast<const float*>(color.pixeladdr(x, y));
            float* f = static_cast<float*>(fast_part.pixeladdr(x, y));
            float* s = static_cast<float*>(slow_part.pixeladdr(x, y));
            for (int k = 0; k < 4; ++k) {
                f[k] = is_slow ? 0.0f : c[k];
                s[k] = is_slow ? c[k] : 0.0f;
            }
        }
    }, paropt(nthreads));
    const std::shared_ptr<const PsfImage> psf = settings.psf_image;
    ImageBuf fast_spread, slow_spread;
    if (!fast(fast_spread, fast_part)
        || !spread_direct(slow_spread, slow_part, radius,
                          [psf](double r) { return psf->footprint(r); }, {}, nthreads)) {
        dst.errorfmt("{}{}", fast_spread.geterror(), slow_spread.geterror());
        return false;
    }
    return ImageBufAlgo::add(dst, fast_spread, slow_spread, {}, nthreads);
}

bool render_layers(ImageBuf& dst, const Scene& scene, const RenderSettings& settings,
                   std::vector<LayerReport>* report, RenderTimings& timings, int nthreads)
{
    if (!scene.flat.empty() || !scene.deep.empty()) {
        dst.errorfmt("the scene has flat or deep content: cut it into layers first "
                     "(decompose_layers)");
        return false;
    }
    const CircleOfConfusion coc(settings.camera, scene.spec.full_width);
    std::vector<LayerReport> depths;
    for (const Layer& layer : scene.layers)
        depths.push_back(describe_layer(layer, coc, nthreads));
    std::vector<size_t> order(scene.layers.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        return depths[a].mean_inverse_depth < depths[b].mean_inverse_depth;
    });

    // Scanline apertures share one profile, sized to the largest blur.
    std::unique_ptr<RowProfile> profile;
    double max_radius = 0.0;
    for (const LayerReport& d : depths)
        max_radius = std::max({ max_radius, 0.5 * std::abs(d.coc_min), 0.5 * std::abs(d.coc_max) });
    const Aperture& aperture = settings.aperture;
    if (aperture.shape == ApertureShape::Disc || aperture.shape == ApertureShape::Polygon) {
        profile = std::make_unique<ApertureProfile>(aperture);
    } else if (aperture.shape == ApertureShape::Mask) {
        auto mask = std::make_unique<MaskProfile>();
        std::string error;
        if (!mask->load(aperture.mask_file, aperture.aspect, error)) {
            dst.errorfmt("{}", error);
            return false;
        }
        profile = std::move(mask);
    }
    ImageBuf result;
    for (size_t i : order) {
        const Layer& layer = scene.layers[i];
        if (depths[i].pixels == 0) {
            if (report)
                report->push_back(depths[i]);
            continue;
        }
        Timer spread_timer;
        ImageBuf radius, spread;
        if (!coc_radius(radius, layer.depth, coc, {}, nthreads)
            || !spread_layer(spread, layer.color, radius, settings, profile.get(),
                             depths[i].psf_pixels, nthreads)) {
            dst.errorfmt("layer '{}': {}", layer.name,
                         radius.has_error() ? radius.geterror() : spread.geterror());
            return false;
        }
        if (report)
            report->push_back(depths[i]);
        timings.spread += spread_timer();
        Timer composite_timer;
        normalize_coverage(spread, nthreads);
        if (!result.initialized()) {
            result = std::move(spread);
        } else {
            ImageBuf composite;
            if (!ImageBufAlgo::over(composite, spread, result, {}, nthreads)) {
                dst.errorfmt("layer '{}': {}", layer.name, composite.geterror());
                return false;
            }
            result = std::move(composite);
        }
        timings.composite += composite_timer();
    }

    const ROI display(scene.spec.full_x, scene.spec.full_x + scene.spec.full_width,
                      scene.spec.full_y, scene.spec.full_y + scene.spec.full_height,
                      0, 1, 0, 4);
    if (!result.initialized()) {  // nothing is covered: a transparent frame
        ImageSpec empty(display, TypeFloat);
        empty.channelnames = { "R", "G", "B", "A" };
        empty.alpha_channel = 3;
        result.reset(empty);
        ImageBufAlgo::zero(result);
    }
    if (settings.window != OutputWindow::Grown) {
        ROI window = settings.window == OutputWindow::Display ? display : scene.spec.roi();
        window.chend = 4;
        ImageBuf cropped;
        ImageBufAlgo::crop(cropped, result, window, nthreads);
        result = std::move(cropped);
    }
    ImageSpec& spec   = result.specmod();
    spec.full_x       = display.xbegin;
    spec.full_y       = display.ybegin;
    spec.full_width   = display.width();
    spec.full_height  = display.height();
    spec.extra_attribs = scene.spec.extra_attribs;
    erase_part_attributes(spec);
    dst = std::move(result);
    return true;
}

}  // namespace

bool parse_output_window(const std::string& name, OutputWindow& window)
{
    for (OutputWindow w : { OutputWindow::Input, OutputWindow::Display, OutputWindow::Grown })
        if (name == output_window_name(w)) {
            window = w;
            return true;
        }
    return false;
}

const char* output_window_name(OutputWindow window)
{
    switch (window) {
    case OutputWindow::Input: return "input";
    case OutputWindow::Display: return "display";
    case OutputWindow::Grown: return "grown";
    }
    return "?";
}

void normalize_coverage(ImageBuf& layer, int nthreads)
{
    const ROI roi = layer.roi();
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            float* p = static_cast<float*>(layer.pixeladdr(x, y));
            if (p[3] > 1.0f) {
                const float scale = 1.0f / p[3];
                for (int c = 0; c < 4; ++c)
                    p[c] *= scale;
            } else if (p[3] < 0.0f) {
                p[3] = 0.0f;
            }
        }
    }, paropt(nthreads));
}

bool render_layered_dof(ImageBuf& dst, const Scene& scene,
                        const RenderSettings& settings,
                        std::vector<LayerReport>* report, RenderTimings* timings,
                        int nthreads)
{
    RenderTimings unused;
    // Errors are reported, never thrown through the API; running out of
    // memory on a huge blur is the one exception the filters can raise.
    try {
        return render_layers(dst, scene, settings, report, timings ? *timings : unused,
                             nthreads);
    } catch (const std::bad_alloc&) {
        dst.errorfmt("out of memory (the layers and the blur are too large)");
        return false;
    }
}

}  // namespace defocus
