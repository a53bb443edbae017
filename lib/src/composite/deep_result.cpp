#include <defocus/composite/deep_result.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/half.h>
#include <OpenImageIO/parallel.h>

#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// The pixels of `spread` (float RGBA, within `window`) that are not
/// black, as a layer's deep samples are: a pixel it does not reach holds no
/// sample. Pixels are indexed within `window`.
DeepLayer lit_pixels(const ImageBuf& spread, const ROI& window, int nthreads)
{
    const ROI roi = spread.roi();
    auto lit = [](const float* p) {
        return p[0] != 0.0f || p[1] != 0.0f || p[2] != 0.0f || p[3] != 0.0f;
    };
    // Each row's lit pixels are counted, then written where the rows
    // before them end: no array grows or is copied again.
    std::vector<size_t> first(size_t(roi.height()) + 1, 0);
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        const float* p = static_cast<const float*>(spread.pixeladdr(roi.xbegin, y));
        size_t n = 0;
        for (int x = 0; x < roi.width(); ++x, p += 4)
            n += lit(p);
        first[size_t(y - roi.ybegin) + 1] = n;
    }, by_rows(nthreads));
    for (size_t r = 1; r < first.size(); ++r)
        first[r] += first[r - 1];
    DeepLayer all;
    all.pixels.resize(first.back());
    all.rgba.resize(4 * first.back());
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        const float* p = static_cast<const float*>(spread.pixeladdr(roi.xbegin, y));
        const uint32_t row = uint32_t(size_t(y - window.ybegin) * size_t(window.width())
                                      + size_t(roi.xbegin - window.xbegin));
        size_t at = first[size_t(y - roi.ybegin)];
        for (int x = 0; x < roi.width(); ++x, p += 4)
            if (lit(p)) {
                all.pixels[at] = row + uint32_t(x);
                std::copy(p, p + 4, &all.rgba[4 * at]);
                ++at;
            }
    }, by_rows(nthreads));
    return all;
}

/// A sample that adds less than this to every channel of its pixel, through
/// the samples in front of it, carries nothing: 1/4000 of an 8-bit display
/// step, below half's precision at 2e-3. Merging other elements' samples
/// in can only hide it more. The spreads' far tails round to such values,
/// and samples behind opaque ones are hidden whole.
constexpr float carries_nothing = 1e-6f;

/// Drops from `layers` (front to back) the samples that carry nothing.
void drop_empty_samples(std::vector<DeepLayer>& layers, const ROI& window)
{
    std::vector<float> through(size_t(window.npixels()), 1.0f);
    for (DeepLayer& layer : layers) {
        size_t kept = 0;
        for (size_t i = 0; i < layer.pixels.size(); ++i) {
            const uint32_t p = layer.pixels[i];
            const float* rgba = &layer.rgba[4 * i];
            const float largest = std::max({ std::abs(rgba[0]), std::abs(rgba[1]),
                                             std::abs(rgba[2]), std::abs(rgba[3]) });
            if (through[p] * largest < carries_nothing)
                continue;
            through[p] *= 1.0f - std::clamp(rgba[3], 0.0f, 1.0f);
            layer.pixels[kept] = p;
            std::copy(rgba, rgba + 4, &layer.rgba[4 * kept]);
            ++kept;
        }
        layer.pixels.resize(kept);
        layer.rgba.resize(4 * kept);
    }
}

/// The window defocus_layers() gives a scene without a layer to spread:
/// nothing grows the display window.
ROI unlit_window(const ImageSpec& scene, OutputWindow window)
{
    return window == OutputWindow::Input ? scene.roi() : scene.roi_full();
}

/// defocus_deep(), the layers spread apart by `spread_apart(sink)`.
template<typename SpreadApart>
bool deep_samples(DeepResult& dst, const LayeredScene& scene, const Camera& camera,
                  OutputWindow window, std::string& error, SpreadApart&& spread_apart,
                  int nthreads)
{
    if (camera.axial_ca != 0.0 || camera.lateral_ca != 0.0) {
        error = "a deep result cannot hold chromatic aberration: each colour has its own alpha";
        return false;
    }
    dst = DeepResult();
    dst.window = unlit_window(scene.spec, window);
    std::vector<size_t> indices;  // of the layers kept, in the scene
    const LayerSink keep = [&](size_t layer, const ImageBuf& lit, const ROI& window) {
        dst.window = window;
        if (uint64_t(window.npixels()) > std::numeric_limits<uint32_t>::max()) {
            error = "the result is too large for a deep image (over 4 billion pixels)";
            return false;
        }
        dst.layers.push_back(lit_pixels(lit, window, nthreads));
        indices.push_back(layer);
        return true;
    };
    if (!spread_apart(keep))
        return false;
    // Back to front as spread; front to back as deep samples run.
    std::reverse(dst.layers.begin(), dst.layers.end());
    std::reverse(indices.begin(), indices.end());
    float in_front = 0.0f;  // the back of the depths of the layer in front
    for (size_t i = 0; i < dst.layers.size(); ++i) {
        const LayerReport& depths = scene.reports[indices[i]];
        DeepLayer& layer = dst.layers[i];
        layer.z = std::max(float(depths.depth_min), in_front);
        layer.zback = std::max(float(depths.depth_max), layer.z);
        in_front = layer.zback;
    }
    drop_empty_samples(dst.layers, dst.window);
    return true;
}

}  // namespace

bool defocus_deep(DeepResult& dst, const LayeredScene& scene, const Camera& camera,
                  const SpreadOptions& spread, const ApertureImages& images,
                  OutputWindow window, std::string& error, std::vector<LayerReport>* report,
                  SpreadStats* stats, int nthreads)
{
    return deep_samples(dst, scene, camera, window, error, [&](const LayerSink& keep) {
        return spread_layers_apart(scene, camera, spread, images, window, keep, error, report,
                                   stats, nthreads);
    }, nthreads);
}

bool defocus_deep_freeing(DeepResult& dst, LayeredScene& scene, const Camera& camera,
                          const SpreadOptions& spread, const ApertureImages& images,
                          OutputWindow window, std::string& error,
                          std::vector<LayerReport>* report, SpreadStats* stats, int nthreads)
{
    return deep_samples(dst, scene, camera, window, error, [&](const LayerSink& keep) {
        return spread_layers_apart_freeing(scene, camera, spread, images, window, keep, error,
                                           report, stats, nthreads);
    }, nthreads);
}

ImageSpec deep_result_spec(const ImageSpec& scene, const ROI& window, TypeDesc color_type)
{
    ImageSpec spec = scene;
    spec.set_roi(window);
    spec.nchannels = 6;
    spec.channelnames = { "R", "G", "B", "A", "Z", "ZBack" };
    // The widest of the channels' types, as OpenImageIO's EXR reader gives
    // it for such a file, so that hosts keep the depths in float.
    spec.set_format(TypeFloat);
    spec.channelformats = { color_type, color_type, color_type, color_type, TypeFloat,
                            TypeFloat };
    spec.alpha_channel = 3;
    spec.z_channel = 4;
    spec.deep = true;
    return spec;
}

ImageBuf deep_buffer(DeepResult&& result, const ImageSpec& scene, TypeDesc color_type,
                     int nthreads)
{
    ImageBuf buffer(deep_result_spec(scene, result.window, color_type));
    DeepData& deep = *buffer.deepdata();
    std::vector<unsigned int> counts(static_cast<size_t>(deep.pixels()), 0u);
    for (const DeepLayer& layer : result.layers)
        for (uint32_t p : layer.pixels)
            ++counts[p];
    deep.set_all_samples(counts);
    // A sample's channels lie at fixed offsets within its record, and a
    // pixel's records follow each other.
    const size_t record = deep.samplesize();
    ptrdiff_t offset[6] = {};
    const auto lit = std::find_if(counts.begin(), counts.end(), [](unsigned n) { return n > 0; });
    if (lit != counts.end()) {
        const int64_t p = lit - counts.begin();
        for (int c = 0; c < 6; ++c)
            offset[c] = static_cast<char*>(deep.data_ptr(p, c, 0))
                        - static_cast<char*>(deep.data_ptr(p, 0, 0));
    }
    const bool half_colour = color_type == TypeHalf;
    std::fill(counts.begin(), counts.end(), 0u);  // now: the samples placed
    for (DeepLayer& layer : result.layers) {
        // A layer has one sample a pixel: its pixels' records are its own.
        parallel_for_chunked(int64_t(0), int64_t(layer.pixels.size()), 0,
                             [&](int64_t begin, int64_t end) {
            for (int64_t i = begin; i < end; ++i) {
                const uint32_t p = layer.pixels[size_t(i)];
                char* at = static_cast<char*>(deep.data_ptr(p, 0, 0)) + counts[p]++ * record;
                const float* colour = &layer.rgba[4 * size_t(i)];
                for (int c = 0; c < 4; ++c) {
                    if (half_colour)
                        *reinterpret_cast<half*>(at + offset[c]) = half(colour[c]);
                    else
                        *reinterpret_cast<float*>(at + offset[c]) = colour[c];
                }
                *reinterpret_cast<float*>(at + offset[4]) = layer.z;
                *reinterpret_cast<float*>(at + offset[5]) = layer.zback;
            }
        }, paropt(nthreads));
        layer = DeepLayer();
    }
    return buffer;
}

}  // namespace defocus
