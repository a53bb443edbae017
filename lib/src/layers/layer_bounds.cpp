#include "layers/layer_bounds.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <utility>

#include <OpenImageIO/parallel.h>

#include "layers/deep_volume.h"
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

/// Folds every covered deep sample into `total`: visit(tally, c, alpha)
/// with its CoC c. A volume sample is visited as the thin samples it is
/// the limit of: a piece of it from every `step` of CoC, each with its
/// share of the sample's optical depth (a thin sample's alpha), and its far
/// end with none. CoC is affine in 1/z at a pixel, so each piece's length
/// in depth follows from the ends'.
template<typename Tally, typename Visit, typename Merge>
void tally_deep_cocs(const Scene& scene, const CircleOfConfusion& coc, double step, Tally& total,
                     const Tally& empty, int nthreads, Visit&& visit, Merge&& merge)
{
    for (const DeepImage& deep : scene.deep)
        tally_rows(deep.roi, total, empty, nthreads, [&](Tally& tally, int y) {
            for (int x = deep.roi.xbegin; x < deep.roi.xend; ++x) {
                const int64_t p = deep.pixel_index(x, y);
                for (uint64_t i = deep.offsets[p]; i < deep.offsets[p + 1]; ++i) {
                    const DeepSample& s = deep.samples[i];
                    if (!(s.a > 0.0f))
                        continue;
                    const double c_near = coc.diameter(s.z, x, y);
                    if (!(s.zback > s.z) || !std::isfinite(s.zback)) {
                        visit(tally, c_near, s.a);
                        continue;
                    }
                    const double c_far = coc.diameter(s.zback, x, y);
                    const double steps = std::ceil((c_far - c_near) / step);
                    const int pieces = steps < 4096.0 ? std::max(1, int(steps)) : 4096;
                    const DeepVolume volume(s);
                    double z = s.z;
                    for (int k = 0; k < pieces; ++k) {
                        const double z_end = volume.depth_at(double(k + 1) / pieces);
                        visit(tally, c_near + (c_far - c_near) * k / pieces,
                              float(volume.density * (z_end - z)));
                        z = z_end;
                    }
                    visit(tally, c_far, 0.0f);
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
        scene, coc, INFINITY, range, Range { INFINITY, -INFINITY }, nthreads,
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
        scene, coc, CocHistogram::bin, h.weight, empty, nthreads,
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

/// Occlusions found row by row (each row's on its own thread), then made
/// distinct.
class OcclusionRows {
public:
    OcclusionRows(const CocHistogram& h, double min_step, int nthreads)
        : m_h(h), m_min_step(min_step), m_nthreads(nthreads)
    {
    }

    /// The CoC of every pixel's front surface (NaN where nothing is), row
    /// by row over `roi`, each pixel against its right and lower
    /// neighbours. Where `discontinuity` is given, only the pixels it
    /// flags: elsewhere no neighbour's CoC differs by more than its step,
    /// and min_step is larger (by more than the rounding of a difference
    /// in float).
    void scan(const ROI& roi, const float* front_coc, const BlurField* discontinuity)
    {
        const size_t first = m_rows.size();
        m_rows.resize(first + roi.height());
        const int width = roi.width(), height = roi.height();
        constexpr double nothing = std::numeric_limits<double>::quiet_NaN();
        parallel_for(0, height, [&](int y) {
            std::vector<Occlusion>& out = m_rows[first + y];
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
        }, by_rows(m_nthreads));
    }

    /// Between the successive samples of each pixel of a deep image: from
    /// the far end of what lies in front (a volume sample is continuous
    /// through its depth) to the next sample's near end.
    void scan_samples(const DeepImage& deep, const CircleOfConfusion& coc)
    {
        const size_t first = m_rows.size();
        m_rows.resize(first + deep.roi.height());
        parallel_for(deep.roi.ybegin, deep.roi.yend, [&](int y) {
            std::vector<Occlusion>& out = m_rows[first + (y - deep.roi.ybegin)];
            std::vector<std::pair<double, double>> spans;  // near and far CoC
            for (int x = deep.roi.xbegin; x < deep.roi.xend; ++x) {
                const int64_t p = deep.pixel_index(x, y);
                spans.clear();
                for (uint64_t i = deep.offsets[p]; i < deep.offsets[p + 1]; ++i) {
                    const DeepSample& s = deep.samples[i];
                    if (s.a > 0.0f) {
                        const double near = coc.diameter(s.z, x, y);
                        spans.emplace_back(near, s.zback > s.z && std::isfinite(s.zback)
                                                     ? coc.diameter(s.zback, x, y)
                                                     : near);
                    }
                }
                std::sort(spans.begin(), spans.end());
                double reached = spans.empty() ? 0.0 : spans[0].second;
                for (size_t i = 1; i < spans.size(); ++i) {
                    if (spans[i].first > reached)
                        add(out, reached, spans[i].first);
                    reached = std::max(reached, spans[i].second);
                }
            }
        }, by_rows(m_nthreads));
    }

    std::vector<Occlusion> distinct()
    {
        std::vector<Occlusion> all;
        for (std::vector<Occlusion>& row : m_rows) {
            std::sort(row.begin(), row.end());
            row.erase(std::unique(row.begin(), row.end()), row.end());
            all.insert(all.end(), row.begin(), row.end());
        }
        std::sort(all.begin(), all.end());
        all.erase(std::unique(all.begin(), all.end()), all.end());
        return all;
    }

private:
    void add(std::vector<Occlusion>& out, double a, double b) const
    {
        if (std::isnan(a) || std::isnan(b)
            || std::abs(a - b) <= std::max(m_min_step, 0.25 * std::min(std::abs(a), std::abs(b))))
            return;
        out.push_back({ m_h.index(std::min(a, b)), m_h.index(std::max(a, b)) });
    }

    /// A step between neighbours is a discontinuity only where it is much
    /// larger than a step beside it: a surface seen at a grazing angle
    /// changes its blur by as much from pixel to pixel, but evenly.
    void edge(std::vector<Occlusion>& out, double before, double a, double b, double after) const
    {
        const double step = std::abs(b - a);
        const double beside = std::min(std::isnan(before) ? 0.0 : std::abs(a - before),
                                       std::isnan(after) ? 0.0 : std::abs(after - b));
        if (step > 2.0 * beside)
            add(out, a, b);
    }

    const CocHistogram& m_h;
    double m_min_step;
    int m_nthreads;
    std::vector<std::vector<Occlusion>> m_rows;
};

/// The CoC of each pixel's front covered sample (NaN where none is).
std::vector<float> front_cocs(const DeepImage& deep, const CircleOfConfusion& coc, int nthreads)
{
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
    return front;
}

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
    OcclusionRows rows(h, min_step, nthreads);
    for (const BlurField& flat : flats)
        rows.scan(flat.roi(), flat.blurs(),
                  min_step > 1.000001 * BlurField::discontinuity_step ? &flat : nullptr);
    for (const DeepImage& deep : scene.deep) {
        rows.scan(deep.roi, front_cocs(deep, coc, nthreads).data(), nullptr);
        rows.scan_samples(deep, coc);
    }
    return rows.distinct();
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
                // The emptiest bin in the farther half of the reach; among
                // equals the farthest, so that a gap between objects is
                // crossed in one layer. (Over all of it, content that
                // thickens with depth, as fog does, was cut a bin at a time.)
                int best = from + (span + 1) / 2;
                for (int i = best; i <= from + span; ++i)
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

LayerBounds choose_layer_bounds(const Scene& scene, const CircleOfConfusion& coc,
                                const LayeringOptions& options, int nthreads)
{
    return layer_bounds(scene, blur_fields(scene, coc, nthreads), coc, options, nthreads);
}

}  // namespace defocus
