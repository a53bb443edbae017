#include "layers/fragments.h"

#include <algorithm>
#include <cmath>

#include <OpenImageIO/parallel.h>

#include "layers/deep_volume.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// What a volume sample leaves in one layer: its optical depth there so
/// far, and the alpha and alpha-weighted depth of what the layer sees.
struct VolumeShare {
    double optical_depth = 0.0, alpha = 0.0, depth_sum = 0.0;

    /// Adds the part [za, zb] of the volume, of optical depth `density` a
    /// unit of depth, that the layer takes with weight w. The part's light
    /// is attenuated along it, so it sits at its depth weighted by
    /// e^(-λ(z - za)), λ = w·density.
    void add(double za, double zb, double w, double density)
    {
        const double lambda = w * density, length = zb - za, tau = lambda * length;
        if (tau <= 0.0)
            return;
        const double covered = std::exp(-optical_depth) * -std::expm1(-tau);
        const double centroid = tau < 1e-6 ? za + 0.5 * length
                                           : za + 1.0 / lambda + length / std::expm1(-tau) + length;
        optical_depth += tau;
        alpha += covered;
        depth_sum += covered * centroid;
    }
};

/// Volume samples [z, zback] as the limit of thin samples through them,
/// as OpenEXR's deep-pixel rules cut them: each slice is shared between the
/// layers as a point at its depth would be (LayerBounds::share), and each
/// layer gets one fragment of what it takes, composited front to back (its
/// alpha 1 - e^(-τ) for the optical depth τ it takes, the sample's colour
/// in proportion, at its alpha-weighted depth). Where the share varies
/// (within a boundary's soft band) the slices are at most 1/8 of the band
/// wide in CoC. Holds its work space, for the samples of a row.
class VolumeSplit {
public:
    explicit VolumeSplit(const LayerBounds& bounds)
        : m_bounds(bounds)
    {
    }

    void operator()(const DeepSample& s, int x, int y, const CircleOfConfusion& coc,
                    std::vector<Fragment>& out)
    {
        const double c_near = coc.diameter(s.z, x, y), c_far = coc.diameter(s.zback, x, y);
        if (!(c_far > c_near)) {
            // No blur tells its depths apart (a pinhole): a point at its
            // middle.
            out.push_back({ s.r, s.g, s.b, s.a, 0.5f * (s.z + s.zback), 0, false, 1, 0 });
            assign_layers(out.back(), x, y, coc, m_bounds);
            return;
        }
        const double half = 0.5 * m_bounds.soft_band();
        m_cuts.assign({ c_near, c_far });
        for (int k = 1; k < m_bounds.count(); ++k)
            for (double c : { m_bounds.boundary(k) - half, m_bounds.boundary(k) + half })
                if (c > c_near && c < c_far)
                    m_cuts.push_back(c);
        std::sort(m_cuts.begin(), m_cuts.end());
        const DeepVolume volume(s);
        auto depth = [&](double c) { return volume.depth_at((c - c_near) / (c_far - c_near)); };
        const int first = m_bounds.share(c_near).front;
        m_shares.clear();
        for (size_t i = 0; i + 1 < m_cuts.size(); ++i) {
            const double a = m_cuts[i], b = m_cuts[i + 1];
            if (!(b > a))
                continue;
            const LayerBounds::Share ends[2] = { m_bounds.share(a + 1e-9 * (b - a)),
                                                 m_bounds.share(b - 1e-9 * (b - a)) };
            const bool even = ends[0].front == ends[1].front
                              && ends[0].front_weight == ends[1].front_weight;
            const int steps = even || half <= 0.0
                                  ? 1
                                  : std::max(1, int(std::ceil((b - a) / (0.25 * half))));
            for (int j = 0; j < steps; ++j) {
                const double ca = a + (b - a) * j / steps, cb = a + (b - a) * (j + 1) / steps;
                const LayerBounds::Share share = m_bounds.share(0.5 * (ca + cb));
                const size_t k = size_t(share.front - first);
                if (m_shares.size() < k + 2)
                    m_shares.resize(k + 2);
                const double za = depth(ca), zb = depth(cb);
                m_shares[k].add(za, zb, share.front_weight, volume.density);
                m_shares[k + 1].add(za, zb, 1.0 - share.front_weight, volume.density);
            }
        }
        const double colour = s.a > 0.0f ? 1.0 / s.a : 0.0;
        for (size_t k = 0; k < m_shares.size(); ++k) {
            const VolumeShare& v = m_shares[k];
            if (v.alpha <= 0.0 || first + int(k) >= m_bounds.count())
                continue;
            const double scale = v.alpha * colour;
            out.push_back({ float(s.r * scale), float(s.g * scale), float(s.b * scale),
                            float(v.alpha), float(v.depth_sum / v.alpha),
                            int16_t(first + int(k)), false, 1.0f, 0.0f });
        }
    }

private:
    const LayerBounds& m_bounds;
    std::vector<double> m_cuts;         ///< CoCs where the share changes how it varies
    std::vector<VolumeShare> m_shares;  ///< per layer from the sample's first
};

}  // namespace

Fragments deep_fragments(const DeepImage& deep, const CircleOfConfusion& coc,
                         const LayerBounds& bounds, int nthreads)
{
    const int64_t n = deep.roi.npixels();
    std::vector<std::vector<Fragment>> rows(deep.roi.height());
    parallel_for(deep.roi.ybegin, deep.roi.yend, [&](int y) {
        std::vector<Fragment>& row = rows[y - deep.roi.ybegin];
        std::vector<DeepSample> samples;
        VolumeSplit split_volume(bounds);
        for (int x = deep.roi.xbegin; x < deep.roi.xend; ++x) {
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
                if (s.zback > s.z && std::isfinite(s.zback)) {
                    split_volume(s, x, y, coc, row);
                } else {
                    row.push_back({ s.r, s.g, s.b, s.a, s.z, 0, false, 1, 0 });
                    assign_layers(row.back(), x, y, coc, bounds);
                }
            }
            std::stable_sort(row.begin() + first, row.end(),
                             [](const Fragment& a, const Fragment& b) { return a.z < b.z; });
            row.push_back({ 0, 0, 0, 0, -1, -1, false, 0, 0 });  // end of pixel
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

double deep_fragment_bytes(const DeepImage& deep, const LayerBounds& bounds)
{
    double fragments = 0.0;
    for (const DeepSample& s : deep.samples)
        fragments += s.zback > s.z && std::isfinite(s.zback) ? bounds.count() : 1;
    return 2.0 * (fragments + double(deep.roi.npixels())) * sizeof(Fragment)
           + double(deep.roi.npixels()) * sizeof(uint64_t);
}

}  // namespace defocus
