// Internal: a flat render's blur map, made once for all that slices it.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include <defocus/layers/mixed_pixels.h>
#include <defocus/scene.h>
#include <defocus/optics/camera.h>

#include "util/float_pixels.h"

namespace defocus {

/// A flat render's pixels with the signed CoC of each (NaN where nothing
/// is), and which of them lie at a depth discontinuity. The layer bounds,
/// the mixed pixels and each pixel's layer all read it, so the CoC of a
/// 4K frame's ten million pixels is taken once.
class BlurField {
public:
    BlurField(const Layer& flat, const CircleOfConfusion& coc, int nthreads);

    const OIIO::ROI& roi() const { return m_roi; }
    const float* color(int x, int y) const { return m_color(x, y); }
    float depth(int x, int y) const { return *m_depth(x, y); }
    float blur(int x, int y) const { return m_blur[index(x, y)]; }
    /// Every pixel's CoC, row by row over roi().
    const float* blurs() const { return m_blur.get(); }
    /// The least and largest CoC of the covered pixels (+inf and -inf
    /// when none is covered).
    float least_blur() const { return m_least; }
    float largest_blur() const { return m_largest; }
    /// Blurs closer than a pixel of CoC look alike.
    static constexpr float discontinuity_step = 1.0f;
    /// True where a 3x3 neighbour's CoC differs from the pixel's by more
    /// than discontinuity_step.
    bool at_discontinuity(int x, int y) const { return m_discontinuity[index(x, y)]; }

    /// Row y's pixels from the window's first column on.
    struct Row {
        const float* color;  ///< RGBA
        const float* depth;
        const float* blur;
        const uint8_t* discontinuity;
    };
    Row row(int y) const
    {
        const size_t i = index(m_roi.xbegin, y);
        return { m_color(m_roi.xbegin, y), m_depth(m_roi.xbegin, y), &m_blur[i],
                 &m_discontinuity[i] };
    }

    /// The CoC of the 3x3 neighbour whose CoC differs most from the
    /// pixel's (its own when none is covered, NaN when it is empty).
    float other_side(int x, int y) const;

private:
    size_t index(int x, int y) const
    {
        return size_t(y - m_roi.ybegin) * size_t(m_roi.width()) + size_t(x - m_roi.xbegin);
    }

    OIIO::ROI m_roi;
    FloatPixels m_color, m_depth;
    std::unique_ptr<float[]> m_blur;
    std::unique_ptr<uint8_t[]> m_discontinuity;
    float m_least = INFINITY, m_largest = -INFINITY;
};

/// The blur field of each of the scene's flat renders.
std::vector<BlurField> blur_fields(const Scene& scene, const CircleOfConfusion& coc, int nthreads);

/// find_mixed_pixels (mixed_pixels.h) over a blur field already made.
std::vector<MixedPixel> find_mixed_pixels(const BlurField& field, int nthreads);

}  // namespace defocus
