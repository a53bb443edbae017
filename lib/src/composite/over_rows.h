// Internal: "over" of a layer's spread onto the frame, in the channels of a
// pass, with its changes from compositing per cell of the aperture: from
// the engine's rows, kept as an image, or from an image; and red and blue
// magnified (lateral chromatic aberration).
#pragma once

#include <algorithm>
#include <cstdint>

#include <Imath/ImathVec.h>
#include <OpenImageIO/imagebuf.h>

#include "composite/frame_spreads.h"
#include "composite/sub_aperture.h"
#include "spread/spread_engine.h"
#include "util/simd.h"

namespace defocus {

/// Which of a pixel's four channels: all bits set, or none.
using Lanes = int64_t __attribute__((vector_size(32)));

/// A spread pixel as "over" composites it: where the layer's own pixels
/// overlap past full coverage, scaled back to it; with `change` (when
/// given: sub-aperture compositing, see SubApertureLayers) added, its alpha
/// kept within [0, 1].
inline d4 composited(d4 spread, const float* change)
{
    const double a = spread[3];
    const double scale = a > 1.0 ? 1.0 / a : 1.0;
    spread *= splat(scale);
    spread.v[3] = a > 1.0 ? 1.0 : std::max(0.0, a);
    if (change) {
        spread += load4(change);
        spread.v[3] = std::clamp(spread[3], 0.0, 1.0);
    }
    return spread;
}

/// "Over" (see Over) of n spread pixels onto the frame's, in the channels
/// `written`; `onto_black`: the frame's pixels count as black; `change`,
/// when given, is added to each (see composited()).
void composite_over(float* out, const double* rgba, int n, const Lanes& written,
                    bool onto_black, const float* change);

/// Composites spread rows over the frame, back to front ("over" on the
/// spread alpha), in the channels of one pass. Within one layer, pixels of
/// different blur overlap additively, so where their coverage adds up past
/// 1 the layer is scaled back to full coverage there (the overlapping
/// parts average instead of adding), keeping alpha within [0, 1]; rounding
/// residue of the prefix sums below 0 is cleared. `onto_black`: the
/// frame's pixels in reach are unset and count as black (the back-most
/// layer), so the frame need not be cleared there first; dark rows are
/// cleared here.
class Over final : public RowSink {
public:
    /// With `cells`, layer `layer`'s changes (see SubApertureLayers) are
    /// composited with it.
    Over(OIIO::ImageBuf& frame, const ChannelPass& pass, bool onto_black,
         const SubApertureLayers* cells = nullptr, size_t layer = 0)
        : m_frame(frame)
        , m_written { pass.colour[0] ? -1 : 0, pass.colour[1] ? -1 : 0, pass.colour[2] ? -1 : 0,
                      pass.alpha ? -1 : 0 }
        , m_onto_black(onto_black)
        , m_cells(cells)
        , m_layer(layer)
    {
    }
    void row(int y, int x_begin, int x_end, const double* rgba) override
    {
        auto put = [&](int x, int end, const float* change) {
            composite_over(static_cast<float*>(m_frame.pixeladdr(x, y)),
                           rgba + size_t(x - x_begin) * 4, end - x, m_written, m_onto_black,
                           change);
        };
        if (m_cells)
            m_cells->each_run(m_layer, y, x_begin, x_end, put);
        else
            put(x_begin, x_end, nullptr);
    }
    void dark(int y, int x_begin, int x_end) override
    {
        if (!m_onto_black)
            return;
        float* out = static_cast<float*>(m_frame.pixeladdr(x_begin, y));
        for (int x = x_begin; x < x_end; ++x, out += 4)
            for (int c = 0; c < 4; ++c)
                if (m_written[c])
                    out[c] = 0.0f;
    }

private:
    OIIO::ImageBuf& m_frame;
    const Lanes m_written;  ///< the channels the pass writes
    const bool m_onto_black;
    const SubApertureLayers* m_cells;
    size_t m_layer;
};

/// Keeps spread rows as an image, for a pass composited later.
class Keep final : public RowSink {
public:
    explicit Keep(OIIO::ImageBuf& image) : m_image(image) {}
    void row(int y, int x_begin, int x_end, const double* rgba) override
    {
        float* out = static_cast<float*>(m_image.pixeladdr(x_begin, y));
        for (size_t i = 0; i < size_t(x_end - x_begin) * 4; ++i)
            out[i] = float(rgba[i]);
    }

private:
    OIIO::ImageBuf& m_image;
};

/// Keeps spread rows as an image, as Keep does, and composites what lies
/// in the frame's window over it, as Over does, in the channels a pass
/// composites as they are.
class KeepAndOver final : public RowSink {
public:
    KeepAndOver(OIIO::ImageBuf& image, OIIO::ImageBuf& frame, const ChannelPass& pass)
        : m_keep(image), m_over(frame, pass, false), m_window(frame.roi())
    {
    }
    void row(int y, int x_begin, int x_end, const double* rgba) override
    {
        m_keep.row(y, x_begin, x_end, rgba);
        const int begin = std::max(x_begin, m_window.xbegin),
                  end = std::min(x_end, m_window.xend);
        if (y >= m_window.ybegin && y < m_window.yend && begin < end)
            m_over.row(y, begin, end, rgba + size_t(begin - x_begin) * 4);
    }

private:
    Keep m_keep;
    Over m_over;
    const OIIO::ROI m_window;
};

/// Composites colour channel `c` of a layer's spread (RGBA) over the frame
/// magnified by `m` about `centre` (lateral chromatic aberration): the
/// light of each spread pixel lands m times as far from the centre, split
/// bilinearly over the four pixels around where it lands, so that the
/// channel keeps its light and its centroid exactly. Alpha is coverage, not
/// light: the frame samples it bilinearly where each pixel came from.
void composite_magnified(OIIO::ImageBuf& frame, const OIIO::ImageBuf& spread, int c,
                         double m, const Imath::V2d& centre, int nthreads);

/// Composites a layer spread apart over the frame, within the frame's
/// window, in the channels of `pass`, with its changes in `cells` (when
/// given).
void composite_image(OIIO::ImageBuf& frame, const OIIO::ImageBuf& layer,
                     const ChannelPass& pass, const SubApertureLayers* cells, size_t index,
                     int nthreads);

/// Puts layer `index`'s changes in `cells` into its spread (float RGBA)
/// where it has any, each such pixel as "over" composites it
/// (composited()): a pass whose red and blue are composited magnified
/// from its spread takes them so.
void add_changes(OIIO::ImageBuf& spread, const SubApertureLayers& cells, size_t index,
                 int nthreads);

}  // namespace defocus
