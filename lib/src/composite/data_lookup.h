// Internal: where a layer's pixels find their data channels.
#pragma once

#include <algorithm>
#include <climits>
#include <string>
#include <vector>

#include <Imath/ImathVec.h>
#include <OpenImageIO/imagebuf.h>

#include <defocus/scene.h>

#include "util/float_pixels.h"

namespace defocus {

/// Where each pixel of a layer finds its data: the source pixel at the same
/// place, or, for a pixel rebuilt behind nearer layers, the nearest pixel
/// of the layer that was seen (the surface it continues); clamped into the
/// data's window, as extend_edges() repeats the outermost pixels.
class DataLookup {
public:
    explicit DataLookup(const Layer& layer)
        : m_data(layer.data.get())
        , m_roi(layer.color.roi())
    {
        if (m_data && layer.rebuilt.initialized())
            find_nearest_seen(layer);
    }

    bool has_data() const { return m_data != nullptr; }
    int channel(const std::string& name) const
    {
        return m_data ? m_data->spec().channelindex(name) : -1;
    }

    /// The data of layer pixel (x, y): has_data() must be true.
    const float* operator()(int x, int y) const
    {
        if (!m_nearest.empty()) {
            const Imath::V2i& n
                = m_nearest[size_t(y - m_roi.ybegin) * m_roi.width() + (x - m_roi.xbegin)];
            if (n.x != INT_MIN) {
                x = n.x;
                y = n.y;
            }
        }
        const OIIO::ROI& source = m_data->roi();
        x = std::clamp(x, source.xbegin, source.xend - 1);
        y = std::clamp(y, source.ybegin, source.yend - 1);
        return static_cast<const float*>(m_data->pixeladdr(x, y));
    }

private:
    /// Two raster sweeps carry each seen pixel's place to its neighbours,
    /// keeping the nearest (an approximate distance transform).
    void find_nearest_seen(const Layer& layer)
    {
        const OIIO::ROI& r = m_roi;
        m_nearest.assign(size_t(r.npixels()), Imath::V2i(INT_MIN, INT_MIN));
        const FloatPixels color(layer.color, r);
        const OIIO::ROI marked = OIIO::roi_intersection(layer.rebuilt.roi(), r);
        auto at = [&](int x, int y) -> Imath::V2i& {
            return m_nearest[size_t(y - r.ybegin) * r.width() + (x - r.xbegin)];
        };
        for (int y = r.ybegin; y < r.yend; ++y)
            for (int x = r.xbegin; x < r.xend; ++x) {
                const bool rebuilt = marked.contains(x, y)
                                     && *static_cast<const uint8_t*>(layer.rebuilt.pixeladdr(x, y));
                if (color(x, y)[3] > 0.0f && !rebuilt)
                    at(x, y) = Imath::V2i(x, y);
            }
        auto relax = [&](int x, int y, int nx, int ny) {
            if (!r.contains(nx, ny) || at(nx, ny).x == INT_MIN)
                return;
            Imath::V2i& here = at(x, y);
            const Imath::V2i& there = at(nx, ny);
            const int64_t d = int64_t(there.x - x) * (there.x - x) + int64_t(there.y - y) * (there.y - y);
            if (here.x == INT_MIN
                || d < int64_t(here.x - x) * (here.x - x) + int64_t(here.y - y) * (here.y - y))
                here = there;
        };
        for (int y = r.ybegin; y < r.yend; ++y)
            for (int x = r.xbegin; x < r.xend; ++x)
                for (auto [dx, dy] : { std::pair(-1, 0), { -1, -1 }, { 0, -1 }, { 1, -1 } })
                    relax(x, y, x + dx, y + dy);
        for (int y = r.yend - 1; y >= r.ybegin; --y)
            for (int x = r.xend - 1; x >= r.xbegin; --x)
                for (auto [dx, dy] : { std::pair(1, 0), { 1, 1 }, { 0, 1 }, { -1, 1 } })
                    relax(x, y, x + dx, y + dy);
    }

    const OIIO::ImageBuf* m_data;
    OIIO::ROI m_roi;
    std::vector<Imath::V2i> m_nearest;  ///< empty when nothing is rebuilt
};

}  // namespace defocus
