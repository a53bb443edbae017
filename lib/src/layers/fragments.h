// Internal: the pieces a flat render's or deep image's pixels are cut
// into, each at one depth with its share of the layers.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <OpenImageIO/imageio.h>

#include <defocus/layers/layering.h>
#include <defocus/layers/mixed_pixels.h>
#include <defocus/optics/camera.h>
#include <defocus/scene.h>

#include "layers/blur_field.h"

namespace defocus {

/// A piece of a pixel's content at one depth: premultiplied colour and
/// alpha, the layers it belongs to and its share of each.
struct Fragment {
    float r, g, b, a, z;
    int16_t front;  ///< layer index; the back share goes to front + 1
    /// Not seen in the pixel: a surface continued behind a nearer one
    /// (MixedPixel::far_continued).
    bool continued;
    float front_weight, back_weight;
};
// A 4K deep frame holds tens of millions of them.
static_assert(sizeof(Fragment) == 32);

/// Every pixel's fragments, sorted front to back.
struct Fragments {
    OIIO::ROI pixels;
    std::vector<uint64_t> offsets;  ///< per pixel, npixels + 1
    std::vector<Fragment> items;

    const OIIO::ROI& roi() const { return pixels; }

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
inline void assign_layers(Fragment& f, double c, const LayerBounds& bounds)
{
    const LayerBounds::Share s = bounds.share(c);
    const SplitWeights w = split_weights(s.front_weight, f.a);
    f.front = s.front;
    f.front_weight = w.front;
    f.back_weight = w.back;
}

/// Layers are bounded in CoC, which at one pixel grows with depth, so
/// they stay in depth order wherever the lens focuses.
inline void assign_layers(Fragment& f, int x, int y, const CircleOfConfusion& coc,
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
                { m.near[0], m.near[1], m.near[2], m.near[3], m.near_z, 0, false, 1, 0 },
                { m.far[0], m.far[1], m.far[2], m.far[3], m.far_z, 0, m.far_continued, 1, 0 },
            };
            for (Fragment f : sides) {
                if (f.a > 0.0f)
                    assign_layers(f, m.x, m.y, coc, bounds);
                m_split.push_back(f);
            }
        }
    }

    const OIIO::ROI& roi() const { return m_field.roi(); }

    /// As Fragments::row.
    template<typename Visit>
    void row(int y, int x0, int x1, Visit&& visit) const
    {
        const BlurField::Row pixels = m_field.row(y);
        const int first = m_field.roi().xbegin;
        MixedWalk mixed = walk_mixed(y, x0);
        for (int x = x0; x < x1; ++x) {
            const int i = x - first;
            if (const Fragment* split = pixels.discontinuity[i] ? mixed.at(x) : nullptr) {
                visit(x, split, 2);
                continue;
            }
            const float* c = pixels.color + 4 * size_t(i);
            Fragment f { c[0], c[1], c[2], c[3], pixels.depth[i], 0, false, 1, 0 };
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
        const OIIO::ROI& roi = m_field.roi();
        MixedWalk mixed = walk_mixed(y, roi.xbegin);
        for (int i = 0; i < roi.width(); ++i) {
            const int x = roi.xbegin + i;
            if (const Fragment* split = pixels.discontinuity[i] ? mixed.at(x) : nullptr) {
                for (const Fragment* f = split; f < split + 2; ++f)
                    if (f->a > 0.0f) {
                        if (f->front_weight > 0.0f)
                            visit(x, f->front);
                        if (f->back_weight > 0.0f)
                            visit(x, f->front + 1);
                    }
                continue;
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
    /// Walks row y's mixed pixels (at discontinuities, ordered by row, then
    /// column) as the columns ascend.
    struct MixedWalk {
        const FlatFragments& fragments;
        int y;
        std::vector<std::pair<int, int>>::const_iterator next;

        /// The near and far fragments of pixel x when it is mixed, else null.
        const Fragment* at(int x)
        {
            const auto& mixed = fragments.m_mixed;
            while (next != mixed.end() && *next < std::pair { y, x })
                ++next;
            if (next == mixed.end() || *next != std::pair { y, x })
                return nullptr;
            return &fragments.m_split[2 * size_t(next - mixed.begin())];
        }
    };
    MixedWalk walk_mixed(int y, int x0) const
    {
        return { *this, y, std::lower_bound(m_mixed.begin(), m_mixed.end(), std::pair { y, x0 }) };
    }

    const BlurField& m_field;
    const LayerBounds& m_bounds;
    std::vector<std::pair<int, int>> m_mixed;  ///< (y, x) of each mixed pixel
    std::vector<Fragment> m_split;             ///< each one's near and far fragment
};

/// A deep image's fragments: samples sorted by Z then ZBack, volume
/// samples split at the layer planes they cross.
Fragments deep_fragments(const DeepImage& deep, const CircleOfConfusion& coc,
                         const LayerBounds& bounds, int nthreads);

/// A bound on the bytes of a deep image's fragments: volume samples are
/// split at every layer plane they cross, and the fragments are held twice
/// for a moment (per row, then together).
double deep_fragment_bytes(const DeepImage& deep, const LayerBounds& bounds);

}  // namespace defocus
