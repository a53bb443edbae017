#include <defocus/layers/layering.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <utility>

#include <OpenImageIO/parallel.h>
#include <OpenImageIO/strutil.h>

#include <defocus/layers/mixed_pixels.h>
#include <defocus/spread/footprint.h>

#include "layers/blur_field.h"
#include "layers/brightness.h"
#include "layers/fragments.h"
#include "layers/layer_bounds.h"
#include "util/bounding_box.h"
#include "util/fresh_image.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

SplitWeights split_weights(float front_weight, float a)
{
    if (front_weight >= 1.0f)
        return { 1.0f, 0.0f };
    // Front part over back part: w·a + (1 - w·a)·s·a = a needs
    // s = (1 - w) / (1 - w·a); the same factor makes the colours add up.
    a = std::clamp(a, 0.0f, 1.0f);
    return { front_weight, (1.0f - front_weight) / (1.0f - front_weight * a) };
}

namespace {

/// Where each of `layers` layers has content in the fragments: the
/// bounding box of the pixels with a share of it; an empty ROI (width 0)
/// for a layer with none.
template<typename Source>
std::vector<ROI> layer_extents(const Source& frags, int layers, int nthreads)
{
    const ROI& roi = frags.roi();
    const size_t n = size_t(roi.height()) * layers;
    // Per row and layer, the first and last column with a share.
    std::vector<int> first(n, std::numeric_limits<int>::max());
    std::vector<int> last(n, std::numeric_limits<int>::min());
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        const size_t row = size_t(y - roi.ybegin) * layers;
        frags.shares(y, [&](int x, int k) {
            if (k < layers) {
                first[row + k] = std::min(first[row + k], x);
                last[row + k] = std::max(last[row + k], x);
            }
        });
    }, by_rows(nthreads));
    std::vector<ROI> extents(layers, ROI(0, 0, 0, 0, 0, 1, 0, 4));
    for (int k = 0; k < layers; ++k)
        for (int y = roi.ybegin; y < roi.yend; ++y) {
            const size_t i = size_t(y - roi.ybegin) * layers + k;
            if (first[i] > last[i])
                continue;
            ROI& e = extents[k];
            e = e.width() > 0 ? ROI(std::min(e.xbegin, first[i]), std::max(e.xend, last[i] + 1),
                                    e.ybegin, y + 1, 0, 1, 0, 4)
                              : ROI(first[i], last[i] + 1, y, y + 1, 0, 1, 0, 4);
        }
    return extents;
}

/// Layer k of the fragments over `window`: each pixel's share of it
/// composited front to back, with the alpha-weighted depth. Returns the
/// pixels that a nearer layer covers and layer k does not, where its
/// hidden background lies, and those where it holds a surface continued
/// behind a nearer one.
template<typename Source>
HiddenPixels extract_layer(const Source& frags, int k, const ROI& window, Layer& layer,
                                   int nthreads)
{
    ImageSpec color_spec(window, TypeFloat);
    color_spec.nchannels = 4;
    color_spec.channelnames = { "R", "G", "B", "A" };
    color_spec.alpha_channel = 3;
    ImageSpec depth_spec(window, TypeFloat);
    depth_spec.nchannels = 1;
    depth_spec.channelnames = { "Z" };
    // Every pixel is written below.
    reset_for_overwrite(layer.color, color_spec, nthreads);
    reset_for_overwrite(layer.depth, depth_spec, nthreads);
    float* const color = static_cast<float*>(layer.color.localpixels());
    float* const depth = static_cast<float*>(layer.depth.localpixels());
    std::vector<uint8_t> hidden(window.npixels());
    // Per row, then added in order: the same sums on any number of threads.
    std::vector<double> light(window.height(), 0.0), coverage(window.height(), 0.0);
    RowRanges continued = empty_rows(window);
    parallel_for(window.ybegin, window.yend, [&](int y) {
        const size_t row = size_t(y - window.ybegin) * window.width();
        frags.row(y, window.xbegin, window.xend, [&](int x, const Fragment* f, int count) {
            double rgba[4] = { 0, 0, 0, 0 }, zsum = 0, wsum = 0;
            const bool nearer = count > 0 && f->a > 0.0f && f->front < k;
            bool is_continued = false;
            for (const Fragment* end = f + count; f < end; ++f) {
                const float w = f->front == k ? f->front_weight
                                : f->front + 1 == k ? f->back_weight : 0.0f;
                if (w <= 0.0f || f->a <= 0.0f)
                    continue;
                const double t = 1.0 - rgba[3];
                is_continued |= f->continued && t > 0.0;
                rgba[0] += t * w * f->r;
                rgba[1] += t * w * f->g;
                rgba[2] += t * w * f->b;
                const double covered = t * w * f->a;
                rgba[3] += covered;
                // Behind full cover a sample adds nothing: 0 × an infinite
                // depth would be NaN.
                if (covered != 0.0)
                    zsum += covered * f->z;
                wsum += covered;
            }
            const size_t p = row + (x - window.xbegin);
            for (int i = 0; i < 4; ++i)
                color[4 * p + i] = float(rgba[i]);
            // Infinite depths (the sky) stay infinite.
            depth[p] = wsum > 0 ? float(std::isinf(zsum) ? INFINITY : zsum / wsum) : 0.0f;
            hidden[p] = nearer && !(color[4 * p + 3] > 0.0f) ? HiddenPixels::hidden
                        : is_continued                            ? HiddenPixels::continued
                                                                  : HiddenPixels::seen;
            if (is_continued) {
                auto& [first, last] = continued[y - window.ybegin];
                first = std::min(first, x);
                last = std::max(last, x);
            }
            if (hidden[p] == HiddenPixels::seen && color[4 * p + 3] > 0.0f) {
                const float* c = &color[4 * p];
                light[y - window.ybegin] += brightness(c);
                coverage[y - window.ybegin] += c[3];
            }
        });
    }, by_rows(nthreads));
    const double all_light = std::accumulate(light.begin(), light.end(), 0.0);
    const double all_coverage = std::accumulate(coverage.begin(), coverage.end(), 0.0);
    return { std::move(hidden), box_of_rows(window, continued),
             all_coverage > 0.0 ? float(all_light / all_coverage) : 1.0f };
}

/// "cutting NAME into N layers needs X, more than the memory limit"
std::string cutting_exceeds(const MemoryLimit& limit, const std::string& name,
                            const LayerBounds& bounds, double bytes)
{
    return limit.exceeded(Strutil::fmt::format("cutting '{}' into {} layers", name,
                                               bounds.count()),
                          bytes);
}

/// Cuts one flat render's or deep image's fragments into layers, appended
/// to `layers`. `held` counts the bytes the layers cut so far hold; false
/// with `error` when the next layer would take them past `limit`, or
/// "cancelled" when `keep_going` (asked before each) says so. The last
/// layer takes the pixels of `render` (if given: the flat render the
/// fragments read, which nothing reads after) where it covers all of it:
/// each of its pixels is read before it is written, and a 4K frame's last
/// layer is 214 MB of fresh pages otherwise.
template<typename Source>
bool slice(const Source& frags, const std::string& base, const LayerBounds& bounds,
           const MemoryLimit& limit, double& held, std::vector<Layer>& layers,
           RebuiltPixels& rebuilt, std::string& error, Layer* render, int nthreads,
           const std::function<bool()>& keep_going)
{
    const double fragment_bytes = frags.bytes();
    // ImageBuf's move may throw, so a vector that grows copies its layers.
    layers.reserve(layers.size() + bounds.count());
    const std::vector<ROI> extents = layer_extents(frags, bounds.count(), nthreads);
    int last = bounds.count() - 1;
    while (last > 0 && extents[last].width() == 0)
        --last;
    for (int k = 0; k < bounds.count(); ++k) {
        if (extents[k].width() == 0)
            continue;
        if (keep_going && !keep_going()) {
            error = "cancelled";
            return false;
        }
        // The hidden background matters as far as it shows through the
        // blurred edges of nearer layers, or spreads its own light out
        // from under them: up to the largest blur of layers 0..k.
        const double fill_distance = box_half_width(0.5 * std::max(std::abs(bounds.boundary(0)),
                                                                   std::abs(bounds.boundary(k + 1))))
                                     + 1.0;
        // A layer is made over its content, and where there are nearer
        // layers, as far around it as their hidden background can be filled.
        const ROI window = k > 0 ? hidden_background_window(extents[k], frags.roi(), fill_distance)
                                 : extents[k];
        const double need = held + fragment_bytes + float_bytes(window.npixels(), 5);
        if (!limit.allows(need)) {
            error = cutting_exceeds(limit, base, bounds, need);
            return false;
        }
        Layer layer;
        layer.name = Strutil::fmt::format("{}.{:02d}", base, k);
        if (render)
            layer.data = render->data;
        const ROI& all = frags.roi();
        if (render && k == last && window.xbegin == all.xbegin && window.xend == all.xend
            && window.ybegin == all.ybegin && window.yend == all.yend) {
            layer.color = std::move(render->color);
            layer.depth = std::move(render->depth);
        }
        const HiddenPixels hidden = extract_layer(frags, k, window, layer, nthreads);
        if (k > 0)
            rebuilt.add(fill_hidden_background(layer, hidden, fill_distance, nthreads));
        crop_to_content(layer, nthreads);
        held += float_bytes(layer.color.roi().npixels(), 5);
        layers.push_back(std::move(layer));
    }
    return true;
}

/// The data of a layer cut from a deep image: at each covered pixel, that
/// of the pixel's sample nearest the layer's depth there (the surface the
/// layer shows), over the layer's window.
std::shared_ptr<const ImageBuf> deep_layer_data(const DeepImage& deep, const Layer& layer,
                                                int nthreads)
{
    const ROI window = layer.color.roi();
    ImageSpec spec(window, TypeFloat);
    spec.nchannels = int(deep.data_names.size());
    spec.channelnames = deep.data_names;
    auto data = std::make_shared<ImageBuf>(spec, InitializePixels::Yes);
    const ROI both = roi_intersection(window, deep.roi);
    const size_t n = deep.data_names.size();
    parallel_for(both.ybegin, both.yend, [&](int y) {
        for (int x = both.xbegin; x < both.xend; ++x) {
            if (!(static_cast<const float*>(layer.color.pixeladdr(x, y))[3] > 0.0f))
                continue;
            const float z = *static_cast<const float*>(layer.depth.pixeladdr(x, y));
            const int64_t p = deep.pixel_index(x, y);
            uint64_t nearest = deep.offsets[p + 1];
            float distance = INFINITY;
            for (uint64_t i = deep.offsets[p]; i < deep.offsets[p + 1]; ++i) {
                const DeepSample& s = deep.samples[i];
                const float d = z < s.z ? s.z - z : z > s.zback ? z - s.zback : 0.0f;
                if (s.a > 0.0f && d < distance) {
                    distance = d;
                    nearest = i;
                }
            }
            if (nearest < deep.offsets[p + 1])
                std::copy_n(&deep.data[nearest * n], n,
                            static_cast<float*>(data->pixeladdr(x, y)));
        }
    }, by_rows(nthreads));
    return data;
}

}  // namespace

bool decompose_layers(Scene&& scene, const CircleOfConfusion& coc,
                      const LayeringOptions& options, LayeredScene& layered,
                      Slicing& slicing, std::string& error, int nthreads,
                      const std::function<bool()>& keep_going)
{
    slicing = Slicing();
    const std::vector<BlurField> flats = blur_fields(scene, coc, nthreads);
    const LayerBounds& bounds = slicing.bounds = layer_bounds(scene, flats, coc, options, nthreads);
    double held = 0.0;
    for (const Layer& layer : scene.layers)
        held += float_bytes(layer.color.roi().npixels(), 5);
    for (size_t i = 0; i < flats.size(); ++i) {
        const std::vector<MixedPixel> mixed = find_mixed_pixels(flats[i], nthreads);
        slicing.mixed_pixels += int64_t(mixed.size());
        const FlatFragments ff(flats[i], mixed, coc, bounds);
        if (!slice(ff, scene.flat[i].name, bounds, options.memory_limit, held, scene.layers,
                   slicing.rebuilt, error, &scene.flat[i], nthreads, keep_going))
            return false;
    }
    for (const DeepImage& deep : scene.deep) {
        const double fragments = held + deep_fragment_bytes(deep, bounds);
        if (!options.memory_limit.allows(fragments)) {
            error = cutting_exceeds(options.memory_limit, deep.name, bounds, fragments);
            return false;
        }
        const size_t first = scene.layers.size();
        if (!slice(deep_fragments(deep, coc, bounds, nthreads), deep.name, bounds,
                   options.memory_limit, held, scene.layers, slicing.rebuilt, error, nullptr,
                   nthreads, keep_going))
            return false;
        if (!deep.data_names.empty())
            for (size_t i = first; i < scene.layers.size(); ++i)
                scene.layers[i].data = deep_layer_data(deep, scene.layers[i], nthreads);
    }
    layered.source = std::move(scene.source);
    layered.spec = std::move(scene.spec);
    layered.layers = std::move(scene.layers);
    order_layers(layered, coc, nthreads);
    scene = Scene();
    return true;
}

}  // namespace defocus
