// Internal: read-only float access to an ImageBuf's pixels over an ROI,
// without a copy when the buffer already holds local float pixels.
#pragma once

#include <memory>

#include <OpenImageIO/imagebuf.h>

namespace defocus {

class FloatPixels {
public:
    FloatPixels() = default;

    /// All channels of `image` over `roi` (which must lie in its data
    /// window).
    FloatPixels(const OIIO::ImageBuf& image, const OIIO::ROI& roi)
        : m_roi(roi)
        , m_nchannels(image.nchannels())
    {
        const OIIO::ImageSpec& spec = image.spec();
        if (image.localpixels() && spec.format == OIIO::TypeFloat
            && image.roi().xbegin == roi.xbegin && image.roi().xend == roi.xend
            && image.roi().ybegin == roi.ybegin && image.roi().yend == roi.yend
            && spec.depth == 1) {
            m_data = static_cast<const float*>(image.localpixels());
            return;
        }
        OIIO::ROI all = roi;
        all.chbegin = 0;
        all.chend   = m_nchannels;
        all.zbegin = 0;
        all.zend   = 1;
        m_storage.reset(new float[size_t(roi.width()) * roi.height() * m_nchannels]);
        image.get_pixels(all, OIIO::TypeFloat, m_storage.get());
        m_data = m_storage.get();
    }

    const OIIO::ROI& roi() const { return m_roi; }
    int nchannels() const { return m_nchannels; }

    /// The channels of pixel (x, y), in absolute image coordinates.
    const float* operator()(int x, int y) const
    {
        return m_data
               + (size_t(y - m_roi.ybegin) * m_roi.width() + (x - m_roi.xbegin))
                     * m_nchannels;
    }

private:
    OIIO::ROI m_roi;
    int m_nchannels = 0;
    const float* m_data = nullptr;
    std::unique_ptr<float[]> m_storage;
};

}  // namespace defocus
