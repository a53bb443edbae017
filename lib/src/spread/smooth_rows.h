// Internal: tent and smooth spreading (spread_smooth.cpp) handed on a row
// at a time, as the engine's is, so that compositing a layer needs no
// image of its spread.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include <OpenImageIO/imagebuf.h>

#include "spread/spread_common.h"
#include "spread/spread_engine.h"

namespace defocus {

class SmoothRows final : public RowSpread {
public:
    /// The spread of `roi` of `src` (all of it when undefined; at most 8
    /// channels) with CoC radii `radius` by the PSF of `order` (2: tent,
    /// 3: smooth); null with `error` where the inputs are wrong. The
    /// images must outlive it.
    static std::unique_ptr<SmoothRows> make(const OIIO::ImageBuf& src,
                                            const OIIO::ImageBuf& radius, int order,
                                            OIIO::ROI roi, std::string& error, int nthreads);

    const OIIO::ROI& extent() const override { return m_ext; }
    /// RGBA only: the sink takes 4 channels.
    void run(const OIIO::ROI& window, RowSink& sink, int nthreads) const override;

    /// The most rows make_rows() writes before it calls written().
    static constexpr int batch_rows = 16;

    /// Makes every row of the extent, top to bottom, a batch at a time:
    /// row r (from the extent's first, 0) is written where out(r) says,
    /// all channels, and written(first, end) is called once rows
    /// [first, end) are.
    void make_rows(const std::function<float*(int)>& out,
                   const std::function<void(int, int)>& written, int nthreads) const;

private:
    SmoothRows(SpreadInputs&& in, int order);

    SpreadInputs m_in;
    int m_order;
    int m_reach;  ///< the widest PSF's half support
    OIIO::ROI m_ext;
};

}  // namespace defocus
