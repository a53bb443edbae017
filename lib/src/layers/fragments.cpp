#include "layers/fragments.h"

#include <algorithm>
#include <cmath>

#include <OpenImageIO/parallel.h>

#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

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
                        float(a), float(0.5 * (cuts[i] + cuts[i + 1])), 0, false, 1, 0 });
    }
}

}  // namespace

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
                    row.push_back({ s.r, s.g, s.b, s.a, s.z, 0, false, 1, 0 });
            }
            std::stable_sort(row.begin() + first, row.end(),
                             [](const Fragment& a, const Fragment& b) { return a.z < b.z; });
            for (size_t i = first; i < row.size(); ++i)
                assign_layers(row[i], x, y, coc, bounds);
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
