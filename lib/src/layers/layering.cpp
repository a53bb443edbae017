#include <defocus/layers/layering.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include <OpenImageIO/parallel.h>
#include <OpenImageIO/strutil.h>

#include <defocus/layers/mixed_pixels.h>
#include <defocus/spread/footprint.h>

#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

LayerBounds::LayerBounds(double coc_near, double coc_far)
    : m_bounds { coc_near, std::max(coc_near, coc_far) }
{
}

LayerBounds::LayerBounds(std::vector<double> boundaries, double soft_band)
    : m_bounds(std::move(boundaries))
    , m_band(std::max(0.0, soft_band))
{
    if (m_bounds.size() < 2)
        m_bounds = { 0.0, 0.0 };
}

LayerBounds::Share LayerBounds::share(double c) const
{
    const int n = count();
    // Layer k holds [boundary(k), boundary(k + 1)).
    const int k = int(std::upper_bound(m_bounds.begin() + 1, m_bounds.end() - 1, c)
                      - (m_bounds.begin() + 1));
    const double half = 0.5 * m_band;
    if (k > 0 && c - m_bounds[k] < half)
        return { k - 1, float((m_bounds[k] + half - c) / m_band) };
    if (k + 1 < n && m_bounds[k + 1] - c < half)
        return { k, float((m_bounds[k + 1] + half - c) / m_band) };
    return { k, 1.0f };
}

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

/// A piece of a pixel's content at one depth: premultiplied colour and
/// alpha, the layers it belongs to and its share of each.
struct Fragment {
    float r, g, b, a, z;
    int front;  ///< layer index; the back share goes to front + 1
    float front_weight, back_weight;
};

/// Every pixel's fragments, sorted front to back.
struct Fragments {
    ROI roi;
    std::vector<uint64_t> offsets;  ///< per pixel, npixels + 1
    std::vector<Fragment> items;
};

/// Layers are bounded in CoC, which at one pixel grows with depth, so
/// they stay in depth order wherever the lens focuses.
void assign_layers(Fragment& f, int x, int y, const CircleOfConfusion& coc,
                   const LayerBounds& bounds)
{
    const LayerBounds::Share s = bounds.share(coc.diameter(f.z, x, y));
    const SplitWeights w = split_weights(s.front_weight, f.a);
    f.front = s.front;
    f.front_weight = w.front;
    f.back_weight = w.back;
}

/// A flat render's fragments: one per pixel, and two for a mixed pixel,
/// its near surface and the rest of it under that.
Fragments flat_fragments(const Layer& flat, const std::vector<MixedPixel>& mixed,
                         const CircleOfConfusion& coc, const LayerBounds& bounds, int nthreads)
{
    Fragments out;
    out.roi = flat.color.roi();
    const int64_t n = out.roi.npixels();
    auto pixel = [&](int x, int y) {
        return int64_t(y - out.roi.ybegin) * out.roi.width() + (x - out.roi.xbegin);
    };
    out.offsets.assign(n + 1, 0);
    for (const MixedPixel& m : mixed)
        out.offsets[pixel(m.x, m.y) + 1] = 1;
    for (int64_t i = 0; i < n; ++i)
        out.offsets[i + 1] += out.offsets[i] + 1;
    out.items.resize(out.offsets[n]);
    auto color = [&](int x, int y) { return static_cast<const float*>(flat.color.pixeladdr(x, y)); };
    auto depth = [&](int x, int y) { return *static_cast<const float*>(flat.depth.pixeladdr(x, y)); };
    parallel_for(out.roi.ybegin, out.roi.yend, [&](int y) {
        for (int x = out.roi.xbegin; x < out.roi.xend; ++x) {
            const float* c = color(x, y);
            Fragment& f = out.items[out.offsets[pixel(x, y)]];
            f = { c[0], c[1], c[2], c[3], depth(x, y), 0, 1, 0 };
            if (f.a > 0.0f)
                assign_layers(f, x, y, coc, bounds);
        }
    }, by_rows(nthreads));
    parallel_for(int64_t(0), int64_t(mixed.size()), [&](int64_t i) {
        const MixedPixel& m = mixed[i];
        Fragment* f = &out.items[out.offsets[pixel(m.x, m.y)]];
        f[0] = { m.near[0], m.near[1], m.near[2], m.near[3], m.near_z, 0, 1, 0 };
        f[1] = { m.far[0], m.far[1], m.far[2], m.far[3], m.far_z, 0, 1, 0 };
        for (int k = 0; k < 2; ++k)
            if (f[k].a > 0.0f)
                assign_layers(f[k], m.x, m.y, coc, bounds);
    }, paropt(nthreads));
    return out;
}

/// Cuts a volume sample [z, zback] at the layer boundaries inside it. Each
/// piece keeps the alpha-split of OpenEXR's deep-pixel rules: a piece
/// covering fraction x of the sample has alpha 1 - (1 - a)^x and colour
/// C·alpha_piece/a, so the pieces composited front to back give back the
/// sample. A piece sits at its middle depth.
void split_volume(const DeepSample& s, const std::vector<double>& planes,
                  std::vector<Fragment>& out)
{
    std::vector<double> cuts { s.z };
    for (double p : planes)
        if (p > s.z && p < s.zback)
            cuts.push_back(p);
    cuts.push_back(s.zback);
    const double length = double(s.zback) - s.z;
    const double log_transmit = std::log1p(-std::min(double(s.a), 1.0 - 1e-7));
    for (size_t i = 0; i + 1 < cuts.size(); ++i) {
        const double x = (cuts[i + 1] - cuts[i]) / length;
        const double a = -std::expm1(x * log_transmit);
        const double scale = s.a > 0.0f ? a / s.a : x;
        out.push_back({ float(s.r * scale), float(s.g * scale), float(s.b * scale),
                        float(a), float(0.5 * (cuts[i] + cuts[i + 1])), 0, 1, 0 });
    }
}

Fragments deep_fragments(const DeepImage& deep, const CircleOfConfusion& coc,
                         const LayerBounds& bounds, int nthreads)
{
    const int64_t n = deep.roi.npixels();
    std::vector<std::vector<Fragment>> rows(deep.roi.height());
    parallel_for(deep.roi.ybegin, deep.roi.yend, [&](int y) {
        std::vector<Fragment>& row = rows[y - deep.roi.ybegin];
        std::vector<DeepSample> samples;
        std::vector<double> planes;  // the layer boundaries' depths at this pixel
        for (int x = deep.roi.xbegin; x < deep.roi.xend; ++x) {
            planes.clear();
            for (int k = 1; k < bounds.count(); ++k)
                planes.push_back(coc.depth_at(bounds.boundary(k), x, y));
            const int64_t p = deep.pixel_index(x, y);
            samples.assign(deep.samples.begin() + deep.offsets[p],
                           deep.samples.begin() + deep.offsets[p + 1]);
            // By Z, then ZBack. (OIIO 2.4's DeepData::sort breaks ties on Z
            // again instead of ZBack.)
            std::stable_sort(samples.begin(), samples.end(),
                             [](const DeepSample& a, const DeepSample& b) {
                                 return a.z < b.z || (a.z == b.z && a.zback < b.zback);
                             });
            const size_t first = row.size();
            for (const DeepSample& s : samples) {
                if (s.a <= 0.0f)
                    continue;
                if (s.zback > s.z && std::isfinite(s.zback))
                    split_volume(s, planes, row);
                else
                    row.push_back({ s.r, s.g, s.b, s.a, s.z, 0, 1, 0 });
            }
            std::stable_sort(row.begin() + first, row.end(),
                             [](const Fragment& a, const Fragment& b) { return a.z < b.z; });
            for (size_t i = first; i < row.size(); ++i)
                assign_layers(row[i], x, y, coc, bounds);
            row.push_back({ 0, 0, 0, 0, -1, -1, 0, 0 });  // end of pixel
        }
    }, by_rows(nthreads));

    Fragments out;
    out.roi = deep.roi;
    out.offsets.reserve(n + 1);
    out.offsets.push_back(0);
    for (const std::vector<Fragment>& row : rows)
        for (const Fragment& f : row) {
            if (f.front < 0)
                out.offsets.push_back(out.items.size());
            else
                out.items.push_back(f);
        }
    return out;
}

/// Layer k of the fragments: each pixel's share of it composited front to
/// back, with the alpha-weighted depth. Returns false when it is empty.
bool extract_layer(const Fragments& frags, int k, Layer& layer, int nthreads)
{
    const ROI& roi = frags.roi;
    ImageSpec color_spec(roi, TypeFloat);
    color_spec.nchannels = 4;
    color_spec.channelnames = { "R", "G", "B", "A" };
    color_spec.alpha_channel = 3;
    ImageSpec depth_spec(roi, TypeFloat);
    depth_spec.nchannels = 1;
    depth_spec.channelnames = { "Z" };
    // Every pixel is written below.
    layer.color.reset(color_spec, InitializePixels::No);
    layer.depth.reset(depth_spec, InitializePixels::No);
    std::atomic<bool> any { false };
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        bool row_any = false;
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const int64_t p = int64_t(y - roi.ybegin) * roi.width() + (x - roi.xbegin);
            double rgba[4] = { 0, 0, 0, 0 }, zsum = 0, wsum = 0;
            for (uint64_t i = frags.offsets[p]; i < frags.offsets[p + 1]; ++i) {
                const Fragment& f = frags.items[i];
                const float w = f.front == k ? f.front_weight
                                : f.front + 1 == k ? f.back_weight : 0.0f;
                if (w <= 0.0f || f.a <= 0.0f)
                    continue;
                const double t = 1.0 - rgba[3];
                rgba[0] += t * w * f.r;
                rgba[1] += t * w * f.g;
                rgba[2] += t * w * f.b;
                const double covered = t * w * f.a;
                rgba[3] += covered;
                zsum += covered * f.z;
                wsum += covered;
            }
            float* c = static_cast<float*>(layer.color.pixeladdr(x, y));
            for (int i = 0; i < 4; ++i)
                c[i] = float(rgba[i]);
            // Infinite depths (the sky) stay infinite.
            *static_cast<float*>(layer.depth.pixeladdr(x, y))
                = wsum > 0 ? float(std::isinf(zsum) ? INFINITY : zsum / wsum) : 0.0f;
            row_any |= wsum > 0;
        }
        if (row_any)
            any = true;
    }, by_rows(nthreads));
    return any;
}

/// The pixels that a layer nearer than k covers and layer k does not:
/// where layer k's hidden background lies.
std::vector<bool> hidden_under_nearer(const Fragments& frags, const Layer& layer, int k)
{
    const ROI& roi = frags.roi;
    std::vector<bool> holes(roi.npixels(), false);
    for (int y = roi.ybegin; y < roi.yend; ++y)
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const int64_t p = int64_t(y - roi.ybegin) * roi.width() + (x - roi.xbegin);
            if (frags.offsets[p] == frags.offsets[p + 1])
                continue;
            const Fragment& front = frags.items[frags.offsets[p]];
            const float a = static_cast<const float*>(layer.color.pixeladdr(x, y))[3];
            holes[p] = front.a > 0.0f && front.front < k && a <= 0.0f;
        }
    return holes;
}

/// A bound on the bytes of a deep image's fragments: volume samples are
/// split at every layer plane they cross, and the fragments are held twice
/// for a moment (per row, then together).
double deep_fragment_bytes(const DeepImage& deep, const LayerBounds& bounds)
{
    double fragments = 0.0;
    for (const DeepSample& s : deep.samples)
        fragments += s.zback > s.z && std::isfinite(s.zback) ? bounds.count() : 1;
    return 2.0 * (fragments + double(deep.roi.npixels())) * sizeof(Fragment)
           + double(deep.roi.npixels()) * sizeof(uint64_t);
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
/// with `error` when the next layer would take them past `limit`.
bool slice(const Fragments& frags, const std::string& base, const LayerBounds& bounds,
           const MemoryLimit& limit, double& held, std::vector<Layer>& layers,
           std::string& error, int nthreads)
{
    const double fragment_bytes =
        double(frags.items.size()) * sizeof(Fragment) + double(frags.offsets.size()) * 8;
    // ImageBuf's move may throw, so a vector that grows copies its layers.
    layers.reserve(layers.size() + bounds.count());
    for (int k = 0; k < bounds.count(); ++k) {
        // A layer is made over all of the fragments' window, then cropped.
        const double need = held + fragment_bytes + float_bytes(frags.roi.npixels(), 5);
        if (!limit.allows(need)) {
            error = cutting_exceeds(limit, base, bounds, need);
            return false;
        }
        Layer layer;
        layer.name = Strutil::fmt::format("{}.{:02d}", base, k);
        if (!extract_layer(frags, k, layer, nthreads))
            continue;
        if (k > 0) {
            // The hidden background matters as far as it shows through the
            // blurred edges of nearer layers, or spreads its own light out
            // from under them: up to the largest blur of layers 0..k.
            const double c = std::max(std::abs(bounds.boundary(0)),
                                      std::abs(bounds.boundary(k + 1)));
            fill_hidden_background(layer, hidden_under_nearer(frags, layer, k),
                                   box_half_width(0.5 * c) + 1.0, nthreads);
        }
        crop_to_content(layer, nthreads);
        held += float_bytes(layer.color.roi().npixels(), 5);
        layers.push_back(std::move(layer));
    }
    return true;
}

}  // namespace

namespace {

/// Alpha-weighted content of a scene's flat and deep parts per bin of CoC.
struct CocHistogram {
    double lo = INFINITY, hi = -INFINITY;
    static constexpr double bin = 0.25;  // pixels of CoC
    std::vector<double> weight;

    int index(double c) const { return std::clamp(int((c - lo) / bin), 0, int(weight.size()) - 1); }
};

/// Calls fn(c, alpha) for every covered flat pixel and deep sample (both
/// ends of a volume sample), rows in parallel; fn must be thread-safe.
template<typename Fn>
void for_each_coc(const Scene& scene, const CircleOfConfusion& coc, Fn&& fn)
{
    for (const Layer& flat : scene.flat) {
        const ROI roi = flat.color.roi();
        parallel_for(roi.ybegin, roi.yend, [&](int y) {
            for (int x = roi.xbegin; x < roi.xend; ++x) {
                const float a = static_cast<const float*>(flat.color.pixeladdr(x, y))[3];
                if (a > 0.0f)
                    fn(y, coc.diameter(*static_cast<const float*>(flat.depth.pixeladdr(x, y)),
                                       x, y),
                       a);
            }
        }, by_rows(0));
    }
    for (const DeepImage& deep : scene.deep)
        parallel_for(deep.roi.ybegin, deep.roi.yend, [&](int y) {
            for (int x = deep.roi.xbegin; x < deep.roi.xend; ++x) {
                const int64_t p = deep.pixel_index(x, y);
                for (uint64_t i = deep.offsets[p]; i < deep.offsets[p + 1]; ++i) {
                    const DeepSample& s = deep.samples[i];
                    if (s.a > 0.0f) {
                        fn(y, coc.diameter(s.z, x, y), s.a);
                        if (s.zback != s.z)
                            fn(y, coc.diameter(s.zback, x, y), 0.0f);
                    }
                }
            }
        }, by_rows(0));
}

CocHistogram coc_histogram(const Scene& scene, const CircleOfConfusion& coc)
{
    CocHistogram h;
    std::mutex mutex;
    for_each_coc(scene, coc, [&](int, double c, float) {
        std::lock_guard<std::mutex> lock(mutex);
        h.lo = std::min(h.lo, c);
        h.hi = std::max(h.hi, c);
    });
    if (!(h.hi > h.lo))
        return h;
    h.weight.assign(size_t((h.hi - h.lo) / CocHistogram::bin) + 1, 0.0);
    for_each_coc(scene, coc, [&](int, double c, float a) {
        std::lock_guard<std::mutex> lock(mutex);
        h.weight[h.index(c)] += a;
    });
    return h;
}

/// A visible depth discontinuity: a nearer surface whose CoC falls in
/// histogram bin `near` beside or in front of a farther one in bin `far`.
/// A layer boundary strictly between the two bins puts them in separate
/// layers, as the method needs wherever their blurs differ visibly.
struct Occlusion {
    int near, far;
    bool operator<(const Occlusion& o) const
    {
        return far != o.far ? far < o.far : near < o.near;
    }
    bool operator==(const Occlusion& o) const { return near == o.near && far == o.far; }
};

/// The distinct occlusions of a scene's flat and deep parts whose sides'
/// CoCs differ by more than `min_step` pixels and by more than a quarter of
/// the smaller blur: between 4-neighbour pixels (a flat pixel, a deep
/// pixel's front sample) and between the successive samples of a deep
/// pixel. Two surfaces spread in one layer go wrong only in a band as wide
/// as their difference in blur at the edge of a blur as wide as the blur
/// itself: a step of a quarter moves a blurred edge by an eighth of its
/// width, and cutting for it costs more (each layer's hidden surface is a
/// guess) than it gains.
std::vector<Occlusion> find_occlusions(const Scene& scene, const CircleOfConfusion& coc,
                                       const CocHistogram& h, double min_step)
{
    std::vector<std::vector<Occlusion>> rows;
    auto add = [&](std::vector<Occlusion>& out, double a, double b) {
        if (std::isnan(a) || std::isnan(b)
            || std::abs(a - b) <= std::max(min_step, 0.25 * std::min(std::abs(a), std::abs(b))))
            return;
        out.push_back({ h.index(std::min(a, b)), h.index(std::max(a, b)) });
    };
    // A step between neighbours is a discontinuity only where it is much
    // larger than a step beside it: a surface seen at a grazing angle
    // changes its blur by as much from pixel to pixel, but evenly.
    auto edge = [&](std::vector<Occlusion>& out, double before, double a, double b, double after) {
        const double step = std::abs(b - a);
        const double beside = std::min(std::isnan(before) ? 0.0 : std::abs(a - before),
                                       std::isnan(after) ? 0.0 : std::abs(after - b));
        if (!(step > 2.0 * beside))
            return;
        add(out, a, b);
    };
    // The CoC of every pixel's front surface (NaN where nothing is), each
    // pixel against its right and lower neighbours.
    auto scan = [&](const ROI& roi, auto&& front_coc) {
        const size_t first = rows.size();
        rows.resize(first + roi.height());
        auto at = [&](int x, int y) {
            return x >= roi.xbegin && x < roi.xend && y >= roi.ybegin && y < roi.yend
                       ? front_coc(x, y)
                       : std::numeric_limits<double>::quiet_NaN();
        };
        parallel_for(roi.ybegin, roi.yend, [&](int y) {
            std::vector<Occlusion>& out = rows[first + (y - roi.ybegin)];
            for (int x = roi.xbegin; x < roi.xend; ++x) {
                const double c = at(x, y);
                edge(out, at(x - 1, y), c, at(x + 1, y), at(x + 2, y));
                edge(out, at(x, y - 1), c, at(x, y + 1), at(x, y + 2));
            }
        }, by_rows(0));
    };
    constexpr double nothing = std::numeric_limits<double>::quiet_NaN();
    for (const Layer& flat : scene.flat)
        scan(flat.color.roi(), [&](int x, int y) {
            const float a = static_cast<const float*>(flat.color.pixeladdr(x, y))[3];
            return a > 0.0f ? coc.diameter(*static_cast<const float*>(flat.depth.pixeladdr(x, y)), x, y)
                            : nothing;
        });
    for (const DeepImage& deep : scene.deep) {
        scan(deep.roi, [&](int x, int y) {
            const int64_t p = deep.pixel_index(x, y);
            double front = nothing;
            float front_z = INFINITY;
            for (uint64_t i = deep.offsets[p]; i < deep.offsets[p + 1]; ++i)
                if (deep.samples[i].a > 0.0f && deep.samples[i].z < front_z) {
                    front_z = deep.samples[i].z;
                    front = coc.diameter(front_z, x, y);
                }
            return front;
        });
        const size_t first = rows.size();
        rows.resize(first + deep.roi.height());
        parallel_for(deep.roi.ybegin, deep.roi.yend, [&](int y) {
            std::vector<Occlusion>& out = rows[first + (y - deep.roi.ybegin)];
            std::vector<double> cocs;
            for (int x = deep.roi.xbegin; x < deep.roi.xend; ++x) {
                const int64_t p = deep.pixel_index(x, y);
                cocs.clear();
                for (uint64_t i = deep.offsets[p]; i < deep.offsets[p + 1]; ++i)
                    if (deep.samples[i].a > 0.0f)
                        cocs.push_back(coc.diameter(deep.samples[i].z, x, y));
                std::sort(cocs.begin(), cocs.end());
                for (size_t i = 1; i < cocs.size(); ++i)
                    add(out, cocs[i - 1], cocs[i]);
            }
        }, by_rows(0));
    }
    std::vector<Occlusion> all;
    for (std::vector<Occlusion>& row : rows) {
        std::sort(row.begin(), row.end());
        row.erase(std::unique(row.begin(), row.end()), row.end());
        all.insert(all.end(), row.begin(), row.end());
    }
    std::sort(all.begin(), all.end());
    all.erase(std::unique(all.begin(), all.end()), all.end());
    return all;
}

/// The fewest boundary bins that separate the two sides of every
/// occlusion (greedy interval stabbing, optimal for intervals: take the
/// occlusion whose far side is nearest, and cut once for it and all the
/// others that one cut can serve). Each cut goes to the emptiest bin its
/// occlusions allow, so that it rarely cuts through a surface.
std::vector<int> separating_bins(const std::vector<Occlusion>& occlusions, const CocHistogram& h,
                                 double soft_band)
{
    // A cut within half the soft band of a side would share that side
    // between the layers it is meant to separate.
    const int margin = int(std::ceil(0.5 * soft_band / CocHistogram::bin));
    std::vector<int> cuts;
    size_t next = 0;  // occlusions before it are separated
    while (next < occlusions.size()) {
        const Occlusion& first = occlusions[next];
        if (!cuts.empty() && first.near < cuts.back() && cuts.back() < first.far) {
            ++next;
            continue;
        }
        // Every occlusion a cut just before first.far would separate;
        // the cut may move down to just above the nearest side among them.
        const int highest = first.far - 1 - margin;
        int lowest = first.near + 1 + margin;
        for (size_t i = next; i < occlusions.size(); ++i)
            if (occlusions[i].near < highest)
                lowest = std::max(lowest, occlusions[i].near + 1 + margin);
        lowest = std::min(lowest, highest);
        int best = highest;
        for (int b = highest; b >= lowest; --b)
            if (h.weight[b] < h.weight[best])
                best = b;
        cuts.push_back(best);
        ++next;
    }
    return cuts;
}

}  // namespace

LayerBounds choose_layer_bounds(const Scene& scene, const CircleOfConfusion& coc,
                                const LayeringOptions& options)
{
    const CocHistogram h = coc_histogram(scene, coc);
    if (h.weight.empty())
        return std::isfinite(h.lo) ? LayerBounds(h.lo, h.lo) : LayerBounds();
    std::vector<double> bounds { h.lo };
    if (options.layers > 0) {
        for (int k = 1; k < options.layers; ++k)
            bounds.push_back(h.lo + (h.hi - h.lo) * k / options.layers);
    } else {
        // Cuts where the image shows one surface over another with a
        // visibly different blur (a step narrower than the soft band and a
        // bin on either side could not be separated anyway), then more
        // where a layer would span more than max_coc_span.
        const double min_step = std::max(1.0, options.soft_band + 2 * CocHistogram::bin);
        const std::vector<int> cuts = separating_bins(find_occlusions(scene, coc, h, min_step),
                                                      h, options.soft_band);
        const int span = std::max(1, int(options.max_coc_span / CocHistogram::bin));
        int from = 0;
        for (size_t k = 0; k <= cuts.size(); ++k) {
            const int to = k < cuts.size() ? cuts[k] : int(h.weight.size());
            while (to - from > span) {
                // The emptiest bin within reach; among equals the farthest,
                // so that a gap between objects is crossed in one layer.
                int best = from + 1;
                for (int i = from + 1; i <= from + span; ++i)
                    if (h.weight[i] <= h.weight[best])
                        best = i;
                bounds.push_back(h.lo + (best + 0.5) * CocHistogram::bin);
                from = best;
            }
            if (k < cuts.size() && cuts[k] > from) {
                bounds.push_back(h.lo + (cuts[k] + 0.5) * CocHistogram::bin);
                from = cuts[k];
            }
        }
    }
    bounds.push_back(h.hi);
    return LayerBounds(std::move(bounds), options.soft_band);
}

bool decompose_layers(Scene&& scene, const CircleOfConfusion& coc,
                      const LayeringOptions& options, LayeredScene& layered,
                      Slicing& slicing, std::string& error, int nthreads)
{
    slicing = Slicing();
    const LayerBounds& bounds = slicing.bounds = choose_layer_bounds(scene, coc, options);
    double held = 0.0;
    for (const Layer& layer : scene.layers)
        held += float_bytes(layer.color.roi().npixels(), 5);
    for (const Layer& flat : scene.flat) {
        const std::vector<MixedPixel> mixed = find_mixed_pixels(flat, coc, nthreads);
        slicing.mixed_pixels += int64_t(mixed.size());
        if (!slice(flat_fragments(flat, mixed, coc, bounds, nthreads), flat.name, bounds,
                   options.memory_limit, held, scene.layers, error, nthreads))
            return false;
    }
    for (const DeepImage& deep : scene.deep) {
        const double fragments = held + deep_fragment_bytes(deep, bounds);
        if (!options.memory_limit.allows(fragments)) {
            error = cutting_exceeds(options.memory_limit, deep.name, bounds, fragments);
            return false;
        }
        if (!slice(deep_fragments(deep, coc, bounds, nthreads), deep.name, bounds,
                   options.memory_limit, held, scene.layers, error, nthreads))
            return false;
    }
    layered.source = std::move(scene.source);
    layered.spec = std::move(scene.spec);
    layered.layers = std::move(scene.layers);
    order_layers(layered, coc, nthreads);
    scene = Scene();
    return true;
}

}  // namespace defocus
