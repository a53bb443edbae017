#include "composite/object_mattes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include <OpenImageIO/parallel.h>
#include <OpenImageIO/strutil.h>

#include <defocus/shot/setting_words.h>

#include "spread/block_levels.h"
#include "util/float_pixels.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

uint32_t float_bits(float f)
{
    uint32_t bits;
    std::memcpy(&bits, &f, sizeof bits);
    return bits;
}

float bits_float(uint32_t bits)
{
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
}

/// The objects of one pixel's data, `channels` its set's channels in the
/// layer's data: an ID is all of the pixel; cryptomatte coverages are
/// normalised to 1 (a pixel's coverage is its alpha, which spreading
/// multiplies back in).
int pixel_objects(const ObjectSet& set, const float* data, const std::vector<int>& channels,
                  PixelObject objects[max_ranks])
{
    if (!set.crypto) {
        if (channels[0] < 0 || !std::isfinite(data[channels[0]]))
            return 0;
        objects[0] = { float_bits(data[channels[0]]), 1.0f };
        return 1;
    }
    int n = 0;
    float total = 0.0f;
    for (size_t r = 0; r + 1 < channels.size() && n < max_ranks; r += 2) {
        if (channels[r] < 0 || channels[r + 1] < 0)
            continue;
        const float coverage = data[channels[r + 1]];
        if (!(coverage > 0.0f) || !std::isfinite(coverage) || !std::isfinite(data[channels[r]]))
            continue;
        objects[n++] = { float_bits(data[channels[r]]), coverage };
        total += coverage;
    }
    for (int k = 0; k < n; ++k)
        objects[k].fraction /= total;
    return n;
}

/// The objects of one pixel, as pixel_objects() finds them.
struct FoundObjects {
    int n = 0;
    PixelObject objects[max_ranks];

    bool operator==(const FoundObjects& other) const
    {
        if (n != other.n)
            return false;
        for (int k = 0; k < n; ++k)
            if (objects[k].id != other.objects[k].id
                || objects[k].fraction != other.objects[k].fraction)
                return false;
        return true;
    }
};

/// The objects a band of rows of one layer shows, in the order a pass
/// over its rows meets them, and its pixels with alpha.
struct BandObjects {
    std::vector<std::pair<uint32_t, Presence>> found;
    std::unordered_map<uint32_t, size_t> index;  ///< into `found`
    int64_t lit = 0;

    /// Rows [y0, y1), columns [x0, x1): objects hold over most of a row,
    /// so each run of pixels that shows the same ones is taken at once.
    void find(const ObjectSet& set, const DataLookup& lookup, const std::vector<int>& channels,
              const FloatPixels& color, int x0, int x1, int y0, int y1)
    {
        auto add_run = [&](const FoundObjects& run, int begin, int end, int y) {
            const ROI pixels(begin, end, y, y + 1);
            for (int k = 0; k < run.n; ++k) {
                auto [it, added] = index.emplace(run.objects[k].id, found.size());
                if (added)
                    found.push_back({ run.objects[k].id, {} });
                found[it->second].second.add(pixels,
                                             run.objects[k].fraction == 1.0f ? end - begin : 0);
            }
        };
        for (int y = y0; y < y1; ++y) {
            FoundObjects run, pixel;
            int run_begin = x0;
            bool in_run = false;
            for (int x = x0; x < x1; ++x) {
                const bool has_alpha = color(x, y)[3] > 0.0f;
                if (has_alpha) {
                    ++lit;
                    pixel.n = pixel_objects(set, lookup(x, y), channels, pixel.objects);
                }
                if (in_run && (!has_alpha || !(pixel == run))) {
                    add_run(run, run_begin, x, y);
                    in_run = false;
                }
                if (has_alpha && !in_run) {
                    run = pixel;
                    run_begin = x;
                    in_run = true;
                }
            }
            if (in_run)
                add_run(run, run_begin, x1, y);
        }
    }
};

/// `roi` of `layer`, grown so that its pixels spread as they do in the
/// whole layer: by the layer's largest CoC radius (the highlight test
/// compares each pixel with the mean over its CoC), then out to whole
/// blocks of the largest merged block.
ROI spread_alike(const ROI& roi, const ROI& layer, const LayerReport& report)
{
    constexpr int block = 1 << max_level;
    const int reach = int(std::ceil(0.5 * std::max(std::abs(report.coc_min),
                                                   std::abs(report.coc_max)))) + 1;
    auto down = [](int v) { return floor_div(v, block) * block; };
    ROI grown(down(roi.xbegin - reach), down(roi.xend - 1 + reach) + block,
              down(roi.ybegin - reach), down(roi.yend - 1 + reach) + block, 0, 1, roi.chbegin,
              roi.chend);
    return roi_intersection(grown, layer);
}

/// Adds the light of layer `layer` that `spread` holds, attenuated by the
/// layers in front of it, to each pixel's `shares`: share m takes channel
/// `channels[m]` of the spread (-1: none). Returns the pixels it added to
/// (undefined: none).
ROI add_attenuated(std::vector<float>& shares, const Coverage& cov, size_t layer,
                   const ImageBuf& spread, const std::array<int, per_spread>& channels,
                   int nthreads)
{
    const ROI lit = roi_intersection(spread.roi(), cov.roi);
    if (lit.width() <= 0 || lit.height() <= 0)
        return ROI();
    parallel_for(lit.ybegin, lit.yend, [&](int y) {
        std::vector<float> t(size_t(lit.width()));
        cov.transmittance(layer, y, lit.xbegin, lit.xend, t.data());
        const float* p = static_cast<const float*>(spread.pixeladdr(lit.xbegin, y));
        float* acc = &shares[cov.index(lit.xbegin, y) * per_spread];
        for (int x = 0; x < lit.width(); ++x, p += spread.nchannels(), acc += per_spread)
            for (size_t m = 0; m < per_spread; ++m)
                if (channels[m] >= 0)
                    acc[m] += p[channels[m]] * t[size_t(x)];
    }, by_rows(nthreads));
    return lit;
}

}  // namespace

bool plausible_ids(const ObjectSet& set, const std::vector<ObjectExtent>& objects,
                   const ROI& frame, std::string& error)
{
    if (set.crypto)
        return true;
    double area = 0.0;  // what the spreads cover, 3 objects at a time
    for (const ObjectExtent& object : objects)
        for (const auto& [layer, presence] : object.layers)
            area += double(presence.roi.npixels()) / per_spread;
    const double spreads = area / std::max(1.0, double(frame.npixels()));
    if (spreads <= 64.0)
        return true;
    const std::string& name = set.channels.front();
    error = Strutil::fmt::format("{}: {} distinct values strewn over the frame, as a continuous channel has: "
                   "as IDs they would take {:.0f} spreads of the frame; carry it with {}",
                   name, objects.size(), spreads, mention("data-channels", name + ":average"));
    return false;
}

std::vector<ObjectExtent> find_objects(const ObjectSet& set, const LayeredScene& scene,
                                       const std::vector<DataLookup>& lookups, int nthreads)
{
    std::vector<ObjectExtent> objects;
    std::unordered_map<uint32_t, size_t> index;
    for (size_t i : lit_layers(scene)) {
        const DataLookup& lookup = lookups[i];
        if (!lookup.has_data())
            continue;
        std::vector<int> channels;
        for (const std::string& name : set.channels)
            channels.push_back(lookup.channel(name));
        const ROI roi = scene.layers[i].color.roi();
        const FloatPixels color(scene.layers[i].color, roi);
        // Bands of rows side by side, joined in order: the objects are met
        // in the order one pass over the rows meets them.
        constexpr int band_rows = 32;
        std::vector<BandObjects> bands(size_t((roi.height() + band_rows - 1) / band_rows));
        parallel_for_each_item(0, int64_t(bands.size()), [&](int64_t b) {
            const int y0 = roi.ybegin + int(b) * band_rows;
            bands[size_t(b)].find(set, lookup, channels, color, roi.xbegin, roi.xend, y0,
                                  std::min(roi.yend, y0 + band_rows));
        }, nthreads);
        int64_t lit = 0;
        for (const BandObjects& band : bands) {
            lit += band.lit;
            for (const auto& [id, presence] : band.found) {
                auto [it, added] = index.emplace(id, objects.size());
                if (added)
                    objects.push_back({ id, {}, {} });
                ObjectExtent& o = objects[it->second];
                o.layers[i].add(presence.roi, presence.whole_pixels);
                o.all = roi_union(o.all, presence.roi);
            }
        }
        for (ObjectExtent& o : objects)
            if (auto it = o.layers.find(i); it != o.layers.end())
                it->second.all_of_layer = it->second.whole_pixels == lit;
    }
    std::sort(objects.begin(), objects.end(), [](const ObjectExtent& a, const ObjectExtent& b) {
        return std::pair(a.all.ybegin, a.all.xbegin) < std::pair(b.all.ybegin, b.all.xbegin);
    });
    // Those whose mattes are spread at all first, so that they share spreads.
    std::stable_partition(objects.begin(), objects.end(),
                          [](const ObjectExtent& o) { return o.spreads(); });
    return objects;
}

int object_spreads(const std::vector<ObjectExtent>& objects)
{
    int spreads = 0;
    for (size_t first = 0; first < objects.size(); first += per_spread)
        spreads += std::any_of(objects.begin() + first,
                               objects.begin() + std::min(objects.size(), first + per_spread),
                               [](const ObjectExtent& o) { return o.spreads(); });
    return spreads;
}

bool spread_objects(const ObjectSet& set, const std::vector<ObjectExtent>& objects,
                    Spreader& spreader, const std::vector<DataLookup>& lookups,
                    const Coverage& cov, TopShares& top, std::string& error)
{
    const LayeredScene& scene = spreader.scene;
    std::vector<float> shares(size_t(cov.roi.npixels()) * per_spread, 0.0f);
    for (size_t first = 0; first < objects.size(); first += per_spread) {
        const size_t count = std::min(per_spread, objects.size() - first);
        std::vector<Layer> layers;
        std::vector<size_t> from;
        layers.reserve(scene.layers.size());  // see Spreader::spread
        ROI touched;
        for (size_t i : lit_layers(scene)) {
            ROI crop;
            bool all_of_layer = true;
            // When each of these objects that lies in the layer is all of
            // its light, their shares there are the layer's spread alpha
            // (channel 0 of cov.layer_alpha).
            std::array<int, per_spread> alpha;
            alpha.fill(-1);
            for (size_t m = 0; m < count; ++m)
                if (auto it = objects[first + m].layers.find(i);
                    it != objects[first + m].layers.end()) {
                    crop = roi_union(crop, it->second.roi);
                    all_of_layer &= it->second.all_of_layer;
                    alpha[m] = 0;
                }
            if (crop.npixels() <= 0)
                continue;
            if (all_of_layer) {
                if (cov.layer_alpha[i].initialized())
                    touched = roi_union(touched, add_attenuated(shares, cov, i, cov.layer_alpha[i],
                                                                alpha, spreader.nthreads));
                continue;
            }
            crop = spread_alike(crop, scene.layers[i].color.roi(), scene.reports[i]);
            std::vector<int> channels;
            for (const std::string& name : set.channels)
                channels.push_back(lookups[i].channel(name));
            layers.push_back(quantity_layer(scene.layers[i], crop,
                                            [&](int x, int y, float q[per_spread]) {
                PixelObject found[max_ranks];
                const int n = pixel_objects(set, lookups[i](x, y), channels, found);
                for (size_t m = 0; m < count; ++m)
                    for (int k = 0; k < n; ++k)
                        if (found[k].id == objects[first + m].id)
                            q[m] += found[k].fraction;
            }, spreader.nthreads));
            from.push_back(i);
        }
        std::array<int, per_spread> spread_channels;
        for (size_t m = 0; m < per_spread; ++m)
            spread_channels[m] = m < count ? int(m) : -1;
        if (!layers.empty()
            && !spreader.spread(std::move(layers), from, [&](size_t i, const ImageBuf& s) {
                   touched = roi_union(touched, add_attenuated(shares, cov, i, s, spread_channels,
                                                               spreader.nthreads));
               }, error))
            return false;
        if (!touched.defined())  // lit nothing in the window
            continue;
        parallel_for(touched.ybegin, touched.yend, [&](int y) {
            for (int x = touched.xbegin; x < touched.xend; ++x) {
                const size_t i = cov.index(x, y);
                for (size_t m = 0; m < count; ++m) {
                    top.insert(i, objects[first + m].id, shares[i * per_spread + m]);
                    shares[i * per_spread + m] = 0.0f;
                }
            }
        }, by_rows(spreader.nthreads));
    }
    return true;
}

void write_objects(ImageBuf& dst, const ObjectSet& set, const TopShares& top,
                   const Coverage& cov, const ImageBuf& result, int nthreads)
{
    const ROI& roi = cov.roi;
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t i = cov.index(x, y);
            float* out = static_cast<float*>(dst.pixeladdr(x, y));
            const PixelObject* shares = top[i];
            if (!set.crypto) {
                out[set.outputs[0]] = shares[0].fraction > 0.0f ? bits_float(shares[0].id) : 0.0f;
                continue;
            }
            const float alpha = static_cast<const float*>(result.pixeladdr(x, y))[3];
            const float scale = cov.alpha[i] > 1e-6f ? alpha / cov.alpha[i] : 0.0f;
            for (int r = 0; r < set.ranks(); ++r) {
                const bool any = shares[r].fraction > 0.0f;
                out[set.outputs[2 * r]] = any ? bits_float(shares[r].id) : 0.0f;
                out[set.outputs[2 * r + 1]] = any ? shares[r].fraction * scale : 0.0f;
            }
        }
    }, by_rows(nthreads));
}

}  // namespace defocus
