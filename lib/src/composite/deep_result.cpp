#include <defocus/composite/deep_result.h>

#include <algorithm>
#include <cstdint>
#include <limits>

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/half.h>
#include <OpenImageIO/parallel.h>

#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// A layer's spread where it is not black: its pixels (indices within the
/// window, row by row) and their premultiplied RGBA.
struct SparseSpread {
    size_t layer = 0;
    std::vector<uint32_t> pixels;
    std::vector<float> rgba;
};

/// The pixels of `spread` (float RGBA) that are not black, as a layer's
/// deep samples are: a pixel it does not reach holds no sample.
SparseSpread sparse_spread(size_t layer, const ImageBuf& spread, int nthreads)
{
    const ROI roi = spread.roi();
    std::vector<SparseSpread> rows(size_t(roi.height()));
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        SparseSpread& row = rows[size_t(y - roi.ybegin)];
        const float* p = static_cast<const float*>(spread.pixeladdr(roi.xbegin, y));
        const uint32_t first = uint32_t(size_t(y - roi.ybegin) * size_t(roi.width()));
        for (int x = 0; x < roi.width(); ++x, p += 4)
            if (p[0] != 0.0f || p[1] != 0.0f || p[2] != 0.0f || p[3] != 0.0f) {
                row.pixels.push_back(first + uint32_t(x));
                row.rgba.insert(row.rgba.end(), p, p + 4);
            }
    }, by_rows(nthreads));
    SparseSpread all;
    all.layer = layer;
    size_t count = 0;
    for (const SparseSpread& row : rows)
        count += row.pixels.size();
    all.pixels.reserve(count);
    all.rgba.reserve(4 * count);
    for (SparseSpread& row : rows) {
        all.pixels.insert(all.pixels.end(), row.pixels.begin(), row.pixels.end());
        all.rgba.insert(all.rgba.end(), row.rgba.begin(), row.rgba.end());
        row = SparseSpread();
    }
    return all;
}

/// The window defocus_layers() gives a scene without a layer to spread:
/// nothing grows the display window.
ROI unlit_window(const ImageSpec& scene, OutputWindow window)
{
    return window == OutputWindow::Input ? scene.roi() : scene.roi_full();
}

/// The samples of `spreads` (back to front) as a deep image over `roi`,
/// front to back in each pixel, each layer over its depths from
/// `reports`, cut where it would reach into the layer in front. Each
/// spread is freed once its samples are placed.
DeepImage deep_samples(std::vector<SparseSpread>& spreads, const ROI& roi,
                       const std::vector<LayerReport>& reports, int nthreads)
{
    DeepImage deep;
    deep.roi = roi;
    deep.roi.chbegin = 0;
    deep.roi.chend = 6;
    const size_t npixels = size_t(roi.npixels());
    std::vector<uint64_t> next(npixels + 1, 0);
    for (const SparseSpread& s : spreads)
        for (uint32_t p : s.pixels)
            ++next[p + 1];
    for (size_t p = 0; p < npixels; ++p)
        next[p + 1] += next[p];
    deep.offsets = next;
    deep.samples.resize(next.back());
    float in_front = 0.0f;  // the back of the depths of the layer in front
    for (auto s = spreads.rbegin(); s != spreads.rend(); ++s) {
        const LayerReport& report = reports[s->layer];
        const float z = std::max(float(report.depth_min), in_front);
        const float zback = std::max(float(report.depth_max), z);
        in_front = zback;
        // A layer has one sample a pixel: its pixels' slots are its own.
        parallel_for_chunked(int64_t(0), int64_t(s->pixels.size()), 0,
                             [&](int64_t begin, int64_t end) {
            for (int64_t i = begin; i < end; ++i) {
                const float* c = &s->rgba[4 * size_t(i)];
                deep.samples[next[s->pixels[size_t(i)]]++] = { c[0], c[1], c[2], c[3], z, zback };
            }
        }, paropt(nthreads));
        *s = SparseSpread();
    }
    return deep;
}

}  // namespace

bool defocus_deep(DeepImage& dst, const LayeredScene& scene, const Camera& camera,
                  const SpreadOptions& spread, const ApertureImages& images,
                  OutputWindow window, std::string& error, std::vector<LayerReport>* report,
                  SpreadTimings* timings, int nthreads)
{
    if (camera.axial_ca != 0.0 || camera.lateral_ca != 0.0) {
        error = "a deep result cannot hold chromatic aberration: each colour has its own alpha";
        return false;
    }
    std::vector<SparseSpread> spreads;
    ROI roi = unlit_window(scene.spec, window);
    const LayerSink keep = [&](size_t layer, const ImageBuf& frame) {
        roi = frame.roi();
        if (uint64_t(roi.npixels()) > std::numeric_limits<uint32_t>::max()) {
            error = "the result is too large for a deep image (over 4 billion pixels)";
            return false;
        }
        spreads.push_back(sparse_spread(layer, frame, nthreads));
        return true;
    };
    if (!spread_layers_apart(scene, camera, spread, images, window, keep, error, report, timings,
                             nthreads))
        return false;
    dst = deep_samples(spreads, roi, scene.reports, nthreads);
    return true;
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

ImageBuf deep_buffer(const DeepImage& image, const ImageSpec& scene, TypeDesc color_type,
                     int nthreads)
{
    ImageBuf buffer(deep_result_spec(scene, image.roi, color_type));
    DeepData& deep = *buffer.deepdata();
    const int64_t npixels = int64_t(image.offsets.size()) - 1;
    std::vector<unsigned int> counts(size_t(std::max<int64_t>(npixels, 0)));
    for (int64_t p = 0; p < npixels; ++p)
        counts[size_t(p)] = unsigned(image.offsets[p + 1] - image.offsets[p]);
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
    parallel_for_chunked(int64_t(0), npixels, 0, [&](int64_t begin, int64_t end) {
        for (int64_t p = begin; p < end; ++p) {
            if (counts[size_t(p)] == 0)
                continue;
            char* at = static_cast<char*>(deep.data_ptr(p, 0, 0));
            for (uint64_t i = image.offsets[p]; i < image.offsets[p + 1]; ++i, at += record) {
                const DeepSample& s = image.samples[i];
                const float colour[4] = { s.r, s.g, s.b, s.a };
                for (int c = 0; c < 4; ++c) {
                    if (half_colour)
                        *reinterpret_cast<half*>(at + offset[c]) = half(colour[c]);
                    else
                        *reinterpret_cast<float*>(at + offset[c]) = colour[c];
                }
                *reinterpret_cast<float*>(at + offset[4]) = s.z;
                *reinterpret_cast<float*>(at + offset[5]) = s.zback;
            }
        }
    }, paropt(nthreads));
    return buffer;
}

}  // namespace defocus
