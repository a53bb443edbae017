#include <defocus/layers/layering.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <numeric>
#include <utility>

#include <OpenImageIO/parallel.h>
#include <OpenImageIO/strutil.h>

#include <defocus/layers/mixed_pixels.h>
#include <defocus/spread/footprint.h>

#include "layers/blur_field.h"
#include "layers/brightness.h"
#include "util/fresh_image.h"
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
    ROI pixels;
    std::vector<uint64_t> offsets;  ///< per pixel, npixels + 1
    std::vector<Fragment> items;

    const ROI& roi() const { return pixels; }

    /// visit(x, fragments, count) for each pixel x of row y in [x0, x1),
    /// with its fragments front to back.
    template<typename Visit>
    void row(int y, int x0, int x1, Visit&& visit) const
    {
        const uint64_t* offset =
            &offsets[int64_t(y - pixels.ybegin) * pixels.width() + (x0 - pixels.xbegin)];
        for (int x = x0; x < x1; ++x, ++offset)
            visit(x, &items[offset[0]], int(offset[1] - offset[0]));
    }

    double bytes() const
    {
        return double(items.size()) * sizeof(Fragment) + double(offsets.size()) * sizeof(uint64_t);
    }

    /// visit(x, k) for each layer k that pixel x of row y has a share of
    /// (more than once where several fragments share it).
    template<typename Visit>
    void shares(int y, Visit&& visit) const
    {
        row(y, pixels.xbegin, pixels.xend, [&](int x, const Fragment* f, int count) {
            for (const Fragment* end = f + count; f < end; ++f)
                if (f->a > 0.0f) {
                    if (f->front_weight > 0.0f)
                        visit(x, f->front);
                    if (f->back_weight > 0.0f)
                        visit(x, f->front + 1);
                }
        });
    }
};

/// The layers of a fragment whose signed CoC is `c`.
void assign_layers(Fragment& f, double c, const LayerBounds& bounds)
{
    const LayerBounds::Share s = bounds.share(c);
    const SplitWeights w = split_weights(s.front_weight, f.a);
    f.front = s.front;
    f.front_weight = w.front;
    f.back_weight = w.back;
}

/// Layers are bounded in CoC, which at one pixel grows with depth, so
/// they stay in depth order wherever the lens focuses.
void assign_layers(Fragment& f, int x, int y, const CircleOfConfusion& coc,
                   const LayerBounds& bounds)
{
    assign_layers(f, coc.diameter(f.z, x, y), bounds);
}

/// A flat render's fragments, made as they are visited: one per pixel, and
/// two for a mixed pixel, its near surface and the rest of it under that.
/// (Held at once, a 4K frame's would take 340 MB, and making them took
/// longer than all else that slices it.)
class FlatFragments {
public:
    FlatFragments(const BlurField& field, const std::vector<MixedPixel>& mixed,
                  const CircleOfConfusion& coc, const LayerBounds& bounds)
        : m_field(field)
        , m_bounds(bounds)
    {
        m_mixed.reserve(mixed.size());
        m_split.reserve(2 * mixed.size());
        for (const MixedPixel& m : mixed) {
            m_mixed.push_back({ m.y, m.x });
            const Fragment sides[2] = {
                { m.near[0], m.near[1], m.near[2], m.near[3], m.near_z, 0, 1, 0 },
                { m.far[0], m.far[1], m.far[2], m.far[3], m.far_z, 0, 1, 0 },
            };
            for (Fragment f : sides) {
                if (f.a > 0.0f)
                    assign_layers(f, m.x, m.y, coc, bounds);
                m_split.push_back(f);
            }
        }
    }

    const ROI& roi() const { return m_field.roi(); }

    /// As Fragments::row.
    template<typename Visit>
    void row(int y, int x0, int x1, Visit&& visit) const
    {
        const BlurField::Row pixels = m_field.row(y);
        const int first = m_field.roi().xbegin;
        // Mixed pixels lie at discontinuities, ordered by row, then column.
        auto mixed = std::lower_bound(m_mixed.begin(), m_mixed.end(), std::pair { y, x0 });
        for (int x = x0; x < x1; ++x) {
            const int i = x - first;
            if (pixels.discontinuity[i]) {
                while (mixed != m_mixed.end() && *mixed < std::pair { y, x })
                    ++mixed;
                if (mixed != m_mixed.end() && *mixed == std::pair { y, x }) {
                    visit(x, &m_split[2 * size_t(mixed - m_mixed.begin())], 2);
                    continue;
                }
            }
            const float* c = pixels.color + 4 * size_t(i);
            Fragment f { c[0], c[1], c[2], c[3], pixels.depth[i], 0, 1, 0 };
            if (f.a > 0.0f)
                assign_layers(f, pixels.blur[i], m_bounds);
            visit(x, &f, 1);
        }
    }

    double bytes() const
    {
        return double(m_split.size()) * sizeof(Fragment)
               + double(m_mixed.size()) * sizeof(m_mixed[0]);
    }

    /// As Fragments::shares, from the CoC alone where a pixel is not
    /// split: a covered pixel (one whose CoC is not NaN) has a share of the
    /// front layer of its CoC, and of the one behind where that share is
    /// less than all (see split_weights), whatever its colour. (The colours
    /// are four times the bytes of the CoCs, and this pass is memory-bound.)
    template<typename Visit>
    void shares(int y, Visit&& visit) const
    {
        const BlurField::Row pixels = m_field.row(y);
        const ROI& roi = m_field.roi();
        auto mixed = std::lower_bound(m_mixed.begin(), m_mixed.end(), std::pair { y, roi.xbegin });
        for (int i = 0; i < roi.width(); ++i) {
            const int x = roi.xbegin + i;
            if (pixels.discontinuity[i]) {
                while (mixed != m_mixed.end() && *mixed < std::pair { y, x })
                    ++mixed;
                if (mixed != m_mixed.end() && *mixed == std::pair { y, x }) {
                    for (const Fragment& f : { m_split[2 * size_t(mixed - m_mixed.begin())],
                                               m_split[2 * size_t(mixed - m_mixed.begin()) + 1] })
                        if (f.a > 0.0f) {
                            if (f.front_weight > 0.0f)
                                visit(x, f.front);
                            if (f.back_weight > 0.0f)
                                visit(x, f.front + 1);
                        }
                    continue;
                }
            }
            if (std::isnan(pixels.blur[i]))
                continue;
            const LayerBounds::Share share = m_bounds.share(pixels.blur[i]);
            if (share.front_weight > 0.0f)
                visit(x, share.front);
            if (share.front_weight < 1.0f)
                visit(x, share.front + 1);
        }
    }

private:
    const BlurField& m_field;
    const LayerBounds& m_bounds;
    std::vector<std::pair<int, int>> m_mixed;  ///< (y, x) of each mixed pixel
    std::vector<Fragment> m_split;             ///< each one's near and far fragment
};

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
    out.pixels = deep.roi;
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
/// pixels that a nearer layer covers and layer k does not: where its
/// hidden background lies.
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
    parallel_for(window.ybegin, window.yend, [&](int y) {
        const size_t row = size_t(y - window.ybegin) * window.width();
        frags.row(y, window.xbegin, window.xend, [&](int x, const Fragment* f, int count) {
            double rgba[4] = { 0, 0, 0, 0 }, zsum = 0, wsum = 0;
            const bool nearer = count > 0 && f->a > 0.0f && f->front < k;
            for (const Fragment* end = f + count; f < end; ++f) {
                const float w = f->front == k ? f->front_weight
                                : f->front + 1 == k ? f->back_weight : 0.0f;
                if (w <= 0.0f || f->a <= 0.0f)
                    continue;
                const double t = 1.0 - rgba[3];
                rgba[0] += t * w * f->r;
                rgba[1] += t * w * f->g;
                rgba[2] += t * w * f->b;
                const double covered = t * w * f->a;
                rgba[3] += covered;
                zsum += covered * f->z;
                wsum += covered;
            }
            const size_t p = row + (x - window.xbegin);
            for (int i = 0; i < 4; ++i)
                color[4 * p + i] = float(rgba[i]);
            // Infinite depths (the sky) stay infinite.
            depth[p] = wsum > 0 ? float(std::isinf(zsum) ? INFINITY : zsum / wsum) : 0.0f;
            hidden[p] = nearer && !(color[4 * p + 3] > 0.0f);
            if (!hidden[p] && color[4 * p + 3] > 0.0f) {
                const float* c = &color[4 * p];
                light[y - window.ybegin] += brightness(c);
                coverage[y - window.ybegin] += c[3];
            }
        });
    }, by_rows(nthreads));
    const double all_light = std::accumulate(light.begin(), light.end(), 0.0);
    const double all_coverage = std::accumulate(coverage.begin(), coverage.end(), 0.0);
    return { std::move(hidden), all_coverage > 0.0 ? float(all_light / all_coverage) : 1.0f };
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
/// with `error` when the next layer would take them past `limit`. The last
/// layer takes the pixels of `render` (if given: the flat render the
/// fragments read, which nothing reads after) where it covers all of it:
/// each of its pixels is read before it is written, and a 4K frame's last
/// layer is 214 MB of fresh pages otherwise.
template<typename Source>
bool slice(const Source& frags, const std::string& base, const LayerBounds& bounds,
           const MemoryLimit& limit, double& held, std::vector<Layer>& layers,
           std::string& error, Layer* render, int nthreads)
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
        const ROI& all = frags.roi();
        if (render && k == last && window.xbegin == all.xbegin && window.xend == all.xend
            && window.ybegin == all.ybegin && window.yend == all.yend) {
            layer.color = std::move(render->color);
            layer.depth = std::move(render->depth);
        }
        const HiddenPixels hidden = extract_layer(frags, k, window, layer, nthreads);
        if (k > 0)
            fill_hidden_background(layer, hidden, fill_distance, nthreads);
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

/// Folds rows into a tally: row(tally, y) for each row of `roi`. Bands of
/// rows run in parallel, each into its own copy of `empty`, and their
/// tallies are merged into `total`, merge(total, tally): a lock per pixel,
/// as this once took, made the histogram a good part of slicing a 4K frame.
template<typename Tally, typename Row, typename Merge>
void tally_rows(const ROI& roi, Tally& total, const Tally& empty, int nthreads, Row&& row,
                Merge&& merge)
{
    std::mutex mutex;
    parallel_for_chunked(roi.ybegin, roi.yend, 0, [&](int64_t first, int64_t last) {
        Tally tally = empty;
        for (int64_t y = first; y < last; ++y)
            row(tally, int(y));
        std::lock_guard<std::mutex> lock(mutex);
        merge(total, tally);
    }, paropt(nthreads));
}

/// Folds every covered deep sample (both ends of a volume sample) into
/// `total`: visit(tally, c, alpha) with its CoC c.
template<typename Tally, typename Visit, typename Merge>
void tally_deep_cocs(const Scene& scene, const CircleOfConfusion& coc, Tally& total,
                     const Tally& empty, int nthreads, Visit&& visit, Merge&& merge)
{
    for (const DeepImage& deep : scene.deep)
        tally_rows(deep.roi, total, empty, nthreads, [&](Tally& tally, int y) {
            for (int x = deep.roi.xbegin; x < deep.roi.xend; ++x) {
                const int64_t p = deep.pixel_index(x, y);
                for (uint64_t i = deep.offsets[p]; i < deep.offsets[p + 1]; ++i) {
                    const DeepSample& s = deep.samples[i];
                    if (s.a > 0.0f) {
                        visit(tally, coc.diameter(s.z, x, y), s.a);
                        if (s.zback != s.z)
                            visit(tally, coc.diameter(s.zback, x, y), 0.0f);
                    }
                }
            }
        }, merge);
}

CocHistogram coc_histogram(const Scene& scene, const std::vector<BlurField>& flats,
                           const CircleOfConfusion& coc, int nthreads)
{
    using Range = std::pair<double, double>;
    Range range { INFINITY, -INFINITY };
    for (const BlurField& flat : flats)
        range = { std::min(range.first, double(flat.least_blur())),
                  std::max(range.second, double(flat.largest_blur())) };
    tally_deep_cocs(
        scene, coc, range, Range { INFINITY, -INFINITY }, nthreads,
        [](Range& r, double c, float) {
            r.first = std::min(r.first, c);
            r.second = std::max(r.second, c);
        },
        [](Range& total, const Range& r) {
            total.first = std::min(total.first, r.first);
            total.second = std::max(total.second, r.second);
        });
    CocHistogram h;
    h.lo = range.first;
    h.hi = range.second;
    if (!(h.hi > h.lo))
        return h;
    const std::vector<double> empty(size_t((h.hi - h.lo) / CocHistogram::bin) + 1, 0.0);
    h.weight = empty;
    auto add = [](std::vector<double>& total, const std::vector<double>& weight) {
        for (size_t i = 0; i < total.size(); ++i)
            total[i] += weight[i];
    };
    for (const BlurField& flat : flats)
        tally_rows(flat.roi(), h.weight, empty, nthreads, [&](std::vector<double>& weight, int y) {
            const BlurField::Row row = flat.row(y);
            for (int i = 0; i < flat.roi().width(); ++i) {
                const float a = row.color[4 * size_t(i) + 3];
                if (a > 0.0f)
                    weight[h.index(row.blur[i])] += a;
            }
        }, add);
    tally_deep_cocs(
        scene, coc, h.weight, empty, nthreads,
        [&](std::vector<double>& weight, double c, float a) { weight[h.index(c)] += a; }, add);
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
std::vector<Occlusion> find_occlusions(const Scene& scene, const std::vector<BlurField>& flats,
                                       const CircleOfConfusion& coc, const CocHistogram& h,
                                       double min_step, int nthreads)
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
    // The CoC of every pixel's front surface (NaN where nothing is), row
    // by row over `roi`, each pixel against its right and lower neighbours.
    // Where `discontinuity` is given, only the pixels it flags: elsewhere
    // no neighbour's CoC differs by more than its step, and min_step is
    // larger (by more than the rounding of a difference in float).
    auto scan = [&](const ROI& roi, const float* front_coc, const BlurField* discontinuity) {
        const size_t first = rows.size();
        rows.resize(first + roi.height());
        const int width = roi.width(), height = roi.height();
        constexpr double nothing = std::numeric_limits<double>::quiet_NaN();
        parallel_for(0, height, [&](int y) {
            std::vector<Occlusion>& out = rows[first + y];
            auto at = [&](int x, int y) {
                return x >= 0 && x < width && y >= 0 && y < height
                           ? double(front_coc[size_t(y) * width + x])
                           : nothing;
            };
            const uint8_t* flagged = discontinuity
                                         ? discontinuity->row(roi.ybegin + y).discontinuity
                                         : nullptr;
            for (int x = 0; x < width; ++x) {
                if (flagged && !flagged[x])
                    continue;
                const double c = at(x, y);
                if (std::isnan(c))
                    continue;
                edge(out, at(x - 1, y), c, at(x + 1, y), at(x + 2, y));
                edge(out, at(x, y - 1), c, at(x, y + 1), at(x, y + 2));
            }
        }, by_rows(nthreads));
    };
    for (const BlurField& flat : flats)
        scan(flat.roi(), flat.blurs(),
             min_step > 1.000001 * BlurField::discontinuity_step ? &flat : nullptr);
    for (const DeepImage& deep : scene.deep) {
        std::vector<float> front(deep.roi.npixels(), std::numeric_limits<float>::quiet_NaN());
        parallel_for(deep.roi.ybegin, deep.roi.yend, [&](int y) {
            for (int x = deep.roi.xbegin; x < deep.roi.xend; ++x) {
                const int64_t p = deep.pixel_index(x, y);
                float front_z = INFINITY;
                for (uint64_t i = deep.offsets[p]; i < deep.offsets[p + 1]; ++i)
                    if (deep.samples[i].a > 0.0f && deep.samples[i].z < front_z) {
                        front_z = deep.samples[i].z;
                        front[size_t(y - deep.roi.ybegin) * deep.roi.width() + (x - deep.roi.xbegin)]
                            = float(coc.diameter(front_z, x, y));
                    }
            }
        }, by_rows(nthreads));
        scan(deep.roi, front.data(), nullptr);
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
        }, by_rows(nthreads));
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

LayerBounds layer_bounds(const Scene& scene, const std::vector<BlurField>& flats,
                         const CircleOfConfusion& coc, const LayeringOptions& options, int nthreads)
{
    const CocHistogram h = coc_histogram(scene, flats, coc, nthreads);
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
        const std::vector<int> cuts = separating_bins(
            find_occlusions(scene, flats, coc, h, min_step, nthreads), h, options.soft_band);
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

std::vector<BlurField> blur_fields(const Scene& scene, const CircleOfConfusion& coc, int nthreads)
{
    std::vector<BlurField> flats;
    flats.reserve(scene.flat.size());
    for (const Layer& flat : scene.flat)
        flats.emplace_back(flat, coc, nthreads);
    return flats;
}

}  // namespace

LayerBounds choose_layer_bounds(const Scene& scene, const CircleOfConfusion& coc,
                                const LayeringOptions& options, int nthreads)
{
    return layer_bounds(scene, blur_fields(scene, coc, nthreads), coc, options, nthreads);
}

bool decompose_layers(Scene&& scene, const CircleOfConfusion& coc,
                      const LayeringOptions& options, LayeredScene& layered,
                      Slicing& slicing, std::string& error, int nthreads)
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
                   error, &scene.flat[i], nthreads))
            return false;
    }
    for (const DeepImage& deep : scene.deep) {
        const double fragments = held + deep_fragment_bytes(deep, bounds);
        if (!options.memory_limit.allows(fragments)) {
            error = cutting_exceeds(options.memory_limit, deep.name, bounds, fragments);
            return false;
        }
        if (!slice(deep_fragments(deep, coc, bounds, nthreads), deep.name, bounds,
                   options.memory_limit, held, scene.layers, error, nullptr, nthreads))
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
