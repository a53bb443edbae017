// Internal: which pixels of a layer are hidden, by pixel coordinates.
#pragma once

#include <cstdint>
#include <vector>

#include <OpenImageIO/imageio.h>

#include <defocus/layers/layering.h>

namespace defocus {

/// A layer's hole flags (HiddenPixels::flags) over its ROI: the hidden
/// pixels are those a nearer layer covers where this one has nothing.
class HoleMap {
public:
    HoleMap(const std::vector<uint8_t>& flags, const OIIO::ROI& roi)
        : m_flags(flags), m_roi(roi)
    {
    }

    const OIIO::ROI& roi() const { return m_roi; }

    /// The flags of row y from column x on.
    const uint8_t* row(int x, int y) const
    {
        return &m_flags[size_t(y - m_roi.ybegin) * m_roi.width() + (x - m_roi.xbegin)];
    }

    bool operator()(int x, int y) const { return *row(x, y) == HiddenPixels::hidden; }

private:
    const std::vector<uint8_t>& m_flags;
    OIIO::ROI m_roi;
};

}  // namespace defocus
