// Data channels carried through defocus by spreading quantities times alpha
// through the layers (see data_channels.h).
#include <defocus/composite/data_channels.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <unordered_map>

#include <Imath/ImathVec.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/parallel.h>
#include <OpenImageIO/strutil.h>

#include <defocus/shot/setting_words.h>

#include "composite/data_lookup.h"
#include "spread/block_levels.h"
#include "util/float_pixels.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// A data value safe to spread: NaN and infinity carry nothing (0), and
/// values beyond +-1e30 are clamped there, as sanitize() clamps colour
/// (float sums of them overflow).
float safe_value(float v)
{
    return std::isfinite(v) ? std::clamp(v, -1e30f, 1e30f) : 0.0f;
}

/// A depth safe to spread: the sky's infinity as the farthest value that
/// sums without overflow.
float safe_depth(float z)
{
    return std::min(z, 1e30f);
}

/// What one spread carries: quantities or objects' mattes, as R, G and B.
constexpr size_t per_spread = 3;

/// Fills up to per_spread quantities of a layer pixel.
using QuantityFill = std::function<void(int x, int y, float q[per_spread])>;

/// `layer` over `roi` with three quantities times its alpha as colour.
Layer quantity_layer(const Layer& layer, const ROI& roi, const QuantityFill& fill, int nthreads)
{
    ImageSpec spec = layer.color.spec();
    spec.set_roi(roi);
    spec.set_format(TypeFloat);
    Layer out { layer.name, ImageBuf(spec, InitializePixels::No), ImageBuf(), {} };
    ROI zroi = roi;
    zroi.chbegin = 0;
    zroi.chend = 1;
    const ROI whole = layer.depth.roi();
    if (whole == zroi && layer.depth.localpixels() && layer.depth.spec().format == TypeFloat)
        // The whole layer: its depth is read, not copied (the layer outlives
        // the spread).
        out.depth = ImageBuf(layer.depth.spec(), const_cast<void*>(layer.depth.localpixels()));
    else
        ImageBufAlgo::crop(out.depth, layer.depth, zroi, nthreads);
    const FloatPixels color(layer.color, roi);
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        float* o = static_cast<float*>(out.color.pixeladdr(roi.xbegin, y));
        for (int x = roi.xbegin; x < roi.xend; ++x, o += 4) {
            const float a = color(x, y)[3];
            float q[per_spread] = { 0.0f, 0.0f, 0.0f };
            if (a > 0.0f)
                fill(x, y, q);
            o[0] = q[0] * a;
            o[1] = q[1] * a;
            o[2] = q[2] * a;
            o[3] = a;
        }
    }, by_rows(nthreads));
    return out;
}

/// One layer's spread quantities: premultiplied float RGBA over what it lights.
using QuantitySink = std::function<void(size_t layer, const ImageBuf& spread)>;

/// Everything the spreads share: the scene, how it is spread, and where.
struct Spreader {
    const LayeredScene& scene;
    const ReachOnly& reach;
    OutputWindow window;
    int nthreads;
    const std::function<bool(int done, int total)>& keep_going;
    int total = 0;  ///< spreads in all
    int done = 0;

    /// Spreads `layers` (quantity layers, back to front, made from the
    /// scene's layers `from`) apart, each handed to `sink` by its scene index.
    /// Thousands of IDs are hundreds of spreads: each first asks whether
    /// to go on ("cancelled" when not), saying how far the stage is.
    bool spread(std::vector<Layer>&& layers, const std::vector<size_t>& from,
                const QuantitySink& sink, std::string& error)
    {
        if (keep_going && !keep_going(done++, total)) {
            error = "cancelled";
            return false;
        }
        LayeredScene alone;
        alone.source = scene.source;
        alone.spec = scene.spec;
        alone.luma = scene.luma;
        const CircleOfConfusion coc(reach.camera, scene.spec.roi_full());
        // ImageBuf's move may throw: a vector that grows copies its layers.
        alone.layers.reserve(layers.size());
        for (size_t k = 0; k < layers.size(); ++k) {
            // A whole layer's quantities have its alpha and depth: its report.
            const bool whole = layers[k].color.roi() == scene.layers[from[k]].color.roi();
            alone.reports.push_back(whole ? scene.reports[from[k]]
                                          : describe_layer(layers[k], coc, nthreads));
            alone.layers.push_back(std::move(layers[k]));
        }
        return spread_layers_apart(alone, reach.camera, reach.spread, reach.images, window,
                                   [&](size_t i, const ImageBuf& s, const ROI&) {
                                       sink(from[i], s);
                                       return true;
                                   },
                                   error, nullptr, nullptr, nthreads);
    }
};

/// Per output pixel, over the result's window: what the first spread of
/// the layers' alphas says about them.
struct Coverage {
    ROI roi;
    std::vector<float> alpha;        ///< the data spread's composite alpha
    std::vector<float> best_weight;  ///< the largest share of any layer so far
    std::vector<int> best_layer;     ///< whose it is (-1: none)
    std::vector<ImageBuf> layer_alpha;  ///< each layer's spread alpha, over what it lights

    size_t index(int x, int y) const
    {
        return size_t(y - roi.ybegin) * roi.width() + (x - roi.xbegin);
    }

    /// The transmittance in front of layer `i` over row y, columns
    /// [x0, x1), into t.
    void transmittance(size_t i, int y, int x0, int x1, float* t) const
    {
        std::fill(t, t + (x1 - x0), 1.0f);
        for (size_t m = i + 1; m < layer_alpha.size(); ++m) {
            if (!layer_alpha[m].initialized())
                continue;
            const ROI& r = layer_alpha[m].roi();
            const int begin = std::max(x0, r.xbegin), end = std::min(x1, r.xend);
            if (y < r.ybegin || y >= r.yend || begin >= end)
                continue;
            const float* a = static_cast<const float*>(layer_alpha[m].pixeladdr(begin, y));
            for (int x = begin; x < end; ++x)
                t[x - x0] *= 1.0f - a[x - begin];
        }
    }
};

/// Where each quantity of a spread goes in the output.
struct QuantityTarget {
    int channel;           ///< dst channel
    DataKind kind;         ///< Average or Dominant
    int front = -1;        ///< for depth: the ZFront channel
    std::string source;    ///< the data channel read ("" = the layer's depth)
};

/// Composites one layer's spread quantities into dst (see data_channels.h).
void composite_quantities(ImageBuf& dst, Coverage& cov, const ImageBuf& spread, size_t layer,
                          const std::vector<QuantityTarget>& targets, bool first, int nthreads)
{
    const ROI lit = roi_intersection(spread.roi(), cov.roi);
    parallel_for(lit.ybegin, lit.yend, [&](int y) {
        const float* s = static_cast<const float*>(spread.pixeladdr(lit.xbegin, y));
        float* out = static_cast<float*>(dst.pixeladdr(lit.xbegin, y));
        for (int x = lit.xbegin; x < lit.xend;
             ++x, s += spread.nchannels(), out += dst.nchannels()) {
            const size_t i = cov.index(x, y);
            const float a = s[3];
            if (first) {
                cov.alpha[i] = a + (1.0f - a) * cov.alpha[i];
                cov.best_weight[i] *= 1.0f - a;
                if (a > cov.best_weight[i] && a > reach_coverage) {
                    cov.best_weight[i] = a;
                    cov.best_layer[i] = int(layer);
                }
            }
            for (size_t j = 0; j < targets.size(); ++j) {
                const QuantityTarget& t = targets[j];
                if (t.kind == DataKind::Average)
                    out[t.channel] = s[j] + (1.0f - a) * out[t.channel];
                else if (cov.best_layer[i] == int(layer) && a > reach_coverage)
                    out[t.channel] = s[j] / a;
                if (t.front >= 0 && a > reach_coverage)
                    out[t.front] = s[j] / a;
            }
        }
    }, by_rows(nthreads));
}

/// The layers with pixels, by index.
std::vector<size_t> lit_layers(const LayeredScene& scene)
{
    std::vector<size_t> from;
    for (size_t i = 0; i < scene.layers.size(); ++i)
        if (scene.reports[i].pixels > 0)
            from.push_back(i);
    return from;
}

/// Spreads the depth and the Average and Dominant channels, three at a
/// time, through every layer; the first spread also fills `cov` (each
/// layer's alpha only when `keep_alphas`: mattes need it).
bool spread_quantities(ImageBuf& dst, Coverage& cov, Spreader& spreader,
                       const std::vector<DataLookup>& lookups,
                       const std::vector<QuantityTarget>& all, bool keep_alphas,
                       std::string& error)
{
    const LayeredScene& scene = spreader.scene;
    const std::vector<size_t> from = lit_layers(scene);
    for (size_t first = 0; first < all.size() || first == 0; first += per_spread) {
        const std::vector<QuantityTarget> targets(
            all.begin() + first, all.begin() + std::min(all.size(), first + per_spread));
        std::vector<Layer> layers;
        layers.reserve(from.size());  // see Spreader::spread
        for (size_t i : from) {
            const Layer& layer = scene.layers[i];
            const DataLookup& lookup = lookups[i];
            std::vector<int> channels;
            for (const QuantityTarget& t : targets)
                channels.push_back(t.source.empty() ? -1 : lookup.channel(t.source));
            const FloatPixels depth(layer.depth, layer.depth.roi());
            layers.push_back(quantity_layer(layer, layer.color.roi(),
                                            [&](int x, int y, float q[per_spread]) {
                for (size_t j = 0; j < channels.size(); ++j)
                    q[j] = targets[j].source.empty() ? safe_depth(*depth(x, y))
                           : channels[j] >= 0       ? safe_value(lookup(x, y)[channels[j]])
                                                    : 0.0f;
            }, spreader.nthreads));
        }
        const bool first_pass = first == 0;
        if (!spreader.spread(std::move(layers), from, [&](size_t i, const ImageBuf& s) {
                composite_quantities(dst, cov, s, i, targets, first_pass, spreader.nthreads);
                const int alpha[] = { 3 };
                if (first_pass && keep_alphas)
                    ImageBufAlgo::channels(cov.layer_alpha[i], s, 1, alpha);
            }, error))
            return false;
    }
    return true;
}

/// An ID channel or a cryptomatte set: what each pixel's data says of the
/// objects it shows.
struct ObjectSet {
    bool crypto = false;
    std::vector<std::string> channels;  ///< ID: one; crypto: id, coverage, id, ...
    std::vector<int> outputs;           ///< dst channels, the same layout
    int ranks() const { return crypto ? int(outputs.size()) / 2 : 1; }
};

/// The most objects read from one pixel.
constexpr int max_ranks = 16;

struct PixelObject {
    uint32_t id;
    float fraction;  ///< of the pixel's alpha
};

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

/// An object and, per layer, the pixels it covers.
struct ObjectExtent {
    uint32_t id;
    std::map<size_t, ROI> layers;
    ROI all;
};

/// Whether `objects` of an ID channel are objects: a continuous channel
/// declared an ID (a user's mistake) has a value per pixel, each strewn
/// over the frame. Past 64 spreads of the frame (9,938 compact IDs take
/// under one, 5,828 values of a colour channel 2,000), false with `error`.
bool plausible_ids(const ObjectSet& set, const std::vector<ObjectExtent>& objects,
                   const ROI& frame, std::string& error)
{
    if (set.crypto)
        return true;
    double area = 0.0;  // what the spreads cover, 3 objects at a time
    for (const ObjectExtent& object : objects)
        for (const auto& [layer, extent] : object.layers)
            area += double(extent.npixels()) / per_spread;
    const double spreads = area / std::max(1.0, double(frame.npixels()));
    if (spreads <= 64.0)
        return true;
    const std::string& name = set.channels.front();
    error = Strutil::fmt::format("{}: {} distinct values strewn over the frame, as a continuous channel has: "
                   "as IDs they would take {:.0f} spreads of the frame; carry it with {}",
                   name, objects.size(), spreads, mention("data-channels", name + ":average"));
    return false;
}

/// Every object of `set` the scene's layers show, ordered by place so that
/// objects spread together lie close.
std::vector<ObjectExtent> find_objects(const ObjectSet& set, const LayeredScene& scene,
                                       const std::vector<DataLookup>& lookups)
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
        PixelObject found[max_ranks];
        for (int y = roi.ybegin; y < roi.yend; ++y)
            for (int x = roi.xbegin; x < roi.xend; ++x) {
                if (!(color(x, y)[3] > 0.0f))
                    continue;
                const int n = pixel_objects(set, lookup(x, y), channels, found);
                for (int k = 0; k < n; ++k) {
                    auto [it, added] = index.emplace(found[k].id, objects.size());
                    if (added)
                        objects.push_back({ found[k].id, {}, {} });
                    ObjectExtent& o = objects[it->second];
                    const ROI pixel(x, x + 1, y, y + 1);
                    o.layers[i] = roi_union(o.layers[i], pixel);
                    o.all = roi_union(o.all, pixel);
                }
            }
    }
    std::sort(objects.begin(), objects.end(), [](const ObjectExtent& a, const ObjectExtent& b) {
        return std::pair(a.all.ybegin, a.all.xbegin) < std::pair(b.all.ybegin, b.all.xbegin);
    });
    return objects;
}

/// Per output pixel, the objects with the largest shares of its alpha,
/// largest first.
class TopShares {
public:
    TopShares(size_t pixels, int ranks)
        : m_ranks(ranks)
        , m_shares(pixels * ranks, PixelObject { 0, 0.0f })
    {
    }

    void insert(size_t pixel, uint32_t id, float share)
    {
        PixelObject* top = &m_shares[pixel * m_ranks];
        if (!(share > top[m_ranks - 1].fraction))
            return;
        int k = m_ranks - 1;
        for (; k > 0 && top[k - 1].fraction < share; --k)
            top[k] = top[k - 1];
        top[k] = { id, share };
    }

    const PixelObject* operator[](size_t pixel) const { return &m_shares[pixel * m_ranks]; }

private:
    int m_ranks;
    std::vector<PixelObject> m_shares;
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

/// Spreads the mattes of `objects`, three at a time, each cropped to where
/// it lies in each layer, and keeps each pixel's largest shares: a matte's
/// spread in one layer, attenuated by the layers in front, summed.
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
        for (size_t i : lit_layers(scene)) {
            ROI crop;
            for (size_t m = 0; m < count; ++m)
                if (auto it = objects[first + m].layers.find(i); it != objects[first + m].layers.end())
                    crop = roi_union(crop, it->second);
            if (crop.npixels() <= 0)
                continue;
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
        ROI touched;
        if (!spreader.spread(std::move(layers), from, [&](size_t i, const ImageBuf& s) {
                const ROI lit = roi_intersection(s.roi(), cov.roi);
                touched = roi_union(touched, lit);
                parallel_for(lit.ybegin, lit.yend, [&](int y) {
                    std::vector<float> t(size_t(lit.width()));
                    cov.transmittance(i, y, lit.xbegin, lit.xend, t.data());
                    const float* p = static_cast<const float*>(s.pixeladdr(lit.xbegin, y));
                    float* acc = &shares[cov.index(lit.xbegin, y) * per_spread];
                    for (int x = 0; x < lit.width(); ++x, p += s.nchannels(), acc += per_spread)
                        for (size_t m = 0; m < count; ++m)
                            acc[m] += p[m] * t[size_t(x)];
                }, by_rows(spreader.nthreads));
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

/// Writes a set's largest shares into dst: cryptomatte as rank pairs,
/// scaled from the data spread's alpha to the result's; an ID as the ID
/// of the largest share (0 where nothing is).
void write_objects(ImageBuf& dst, const ObjectSet& set, const TopShares& top, const Coverage& cov,
                   const ImageBuf& result, int nthreads)
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

/// Divides the Average channels by the alpha they were composited with,
/// and makes each normal of three channels unit length again.
void finish_quantities(ImageBuf& dst, const Coverage& cov, const std::vector<int>& averages,
                       const std::vector<std::array<int, 3>>& normals, int nthreads)
{
    const ROI& roi = cov.roi;
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            float* out = static_cast<float*>(dst.pixeladdr(x, y));
            const float a = cov.alpha[cov.index(x, y)];
            for (int c : averages)
                out[c] = a > reach_coverage ? out[c] / a : 0.0f;
            for (const auto& n : normals) {
                const float length = std::sqrt(out[n[0]] * out[n[0]] + out[n[1]] * out[n[1]]
                                               + out[n[2]] * out[n[2]]);
                if (length > 0.0f)
                    for (int c : n)
                        out[c] /= length;
            }
        }
    }, by_rows(nthreads));
}

/// The dst channel of each quantity and set of `plan`, named as
/// DataPlan::output_channels() names them; the normals grouped by three
/// channels of one set.
void lay_out(const DataPlan& plan, const std::vector<std::string>& names,
             std::vector<QuantityTarget>& targets, std::vector<ObjectSet>& sets,
             std::vector<int>& averages, std::vector<std::array<int, 3>>& normals)
{
    auto channel = [&](const std::string& name) {
        return int(std::find(names.begin(), names.end(), name) - names.begin());
    };
    if (plan.depth) {
        targets.push_back({ channel("Z"), DataKind::Average, channel("ZFront"), "" });
        averages.push_back(channel("Z"));
    }
    std::map<std::string, std::vector<int>> normal_sets;
    for (const DataChannel& c : plan.channels) {
        if (c.kind == DataKind::Id) {
            sets.push_back({ false, { c.name }, { channel(c.name) } });
            continue;
        }
        targets.push_back({ channel(c.name), c.kind, -1, c.name });
        if (c.kind == DataKind::Average)
            averages.push_back(channel(c.name));
        if (c.normal)
            normal_sets[c.name.substr(0, c.name.rfind('.'))].push_back(channel(c.name));
    }
    for (const auto& [set, channels] : normal_sets)
        if (channels.size() == 3)
            normals.push_back({ channels[0], channels[1], channels[2] });
    for (const CryptoSet& crypto : plan.crypto) {
        ObjectSet set { true, crypto.channels, {} };
        for (const std::string& name : crypto.channels)
            set.outputs.push_back(channel(name));
        sets.push_back(std::move(set));
    }
}

}  // namespace

bool data_channels(ImageBuf& dst, const ImageBuf& result, const LayeredScene& scene,
                   const Camera& camera, const SpreadOptions& spread,
                   const ApertureImages& images, OutputWindow window, const DataPlan& plan,
                   int nthreads, const std::function<bool(int, int)>& keep_going)
{
    const ROI roi = result.roi();
    const std::vector<std::string> names = plan.output_channels();
    ImageSpec spec(roi.width(), roi.height(), int(names.size()), TypeFloat);
    spec.x = roi.xbegin;
    spec.y = roi.ybegin;
    spec.channelnames = names;
    dst.reset(spec, InitializePixels::Yes);
    const ReachOnly reach = reach_only(camera, spread, images);
    Spreader spreader { scene, reach, window, nthreads, keep_going };
    std::vector<DataLookup> lookups;
    for (const Layer& layer : scene.layers)
        lookups.emplace_back(layer);
    const size_t pixels = size_t(roi.npixels());
    Coverage cov { roi, std::vector<float>(pixels, 0.0f), std::vector<float>(pixels, 0.0f),
                   std::vector<int>(pixels, -1), std::vector<ImageBuf>(scene.layers.size()) };
    std::vector<QuantityTarget> targets;
    std::vector<ObjectSet> sets;
    std::vector<int> averages;
    std::vector<std::array<int, 3>> normals;
    lay_out(plan, names, targets, sets, averages, normals);
    std::string error;
    std::vector<std::vector<ObjectExtent>> objects;
    auto spreads = [](size_t items) { return int((items + per_spread - 1) / per_spread); };
    spreader.total = std::max(1, spreads(targets.size()));
    for (const ObjectSet& set : sets) {
        objects.push_back(find_objects(set, scene, lookups));
        if (!plausible_ids(set, objects.back(), roi, error)) {
            dst.errorfmt("{}", error);
            return false;
        }
        spreader.total += spreads(objects.back().size());
    }
    if (!spread_quantities(dst, cov, spreader, lookups, targets, !sets.empty(), error)) {
        dst.errorfmt("{}", error);
        return false;
    }
    finish_quantities(dst, cov, averages, normals, nthreads);
    for (size_t s = 0; s < sets.size(); ++s) {
        TopShares top(pixels, sets[s].ranks());
        if (!spread_objects(sets[s], objects[s], spreader, lookups, cov, top, error)) {
            dst.errorfmt("{}", error);
            return false;
        }
        write_objects(dst, sets[s], top, cov, result, nthreads);
    }
    return true;
}

}  // namespace defocus
