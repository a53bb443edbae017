#include "spread/spread_common.h"

#include <defocus/spread/hybrid.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

#include <OpenImageIO/parallel.h>

#include "spread/pixels_alone.h"
#include "util/fresh_image.h"
#include "util/parallel_rows.h"

namespace defocus {

using OIIO::ROI;

namespace {

double max_radius(OIIO::ImageBuf& dst, const FloatPixels& pixels,
                  const FloatPixels& radii, int nthreads)
{
    const ROI& roi = radii.roi();
    std::vector<double> row_max(roi.height(), 0.0);
    OIIO::parallel_for(roi.ybegin, roi.yend, [&](int y) {
        double m = 0.0;
        for (int x = roi.xbegin; x < roi.xend; ++x)
            if (!is_zero(pixels(x, y), pixels.nchannels()))
                m = std::max(m, double(*radii(x, y)));
        row_max[y - roi.ybegin] = m;
    }, by_rows(nthreads));
    const double m = row_max.empty() ? 0.0 : *std::max_element(row_max.begin(), row_max.end());
    // Beyond this a footprint would not fit in memory: a clamped CoC never
    // comes near it.
    const double limit = 1 << 20;
    if (!(m <= limit)) {
        dst.errorfmt("spread: CoC radius {} is out of range (limit {})", m, limit);
        return -1.0;
    }
    return m;
}

}  // namespace

SpreadInputs prepare_spread(OIIO::ImageBuf& dst, const OIIO::ImageBuf& src,
                            const OIIO::ImageBuf& radius, ROI roi, int nthreads)
{
    SpreadInputs in;
    if (!src.initialized() || !radius.initialized()) {
        dst.errorfmt("spread: uninitialized input");
        return in;
    }
    if (radius.nchannels() != 1) {
        dst.errorfmt("spread: the radius image must have one channel, not {}",
                     radius.nchannels());
        return in;
    }
    if (!roi.defined())
        roi = src.roi();
    roi.chbegin = 0;
    roi.chend   = src.nchannels();
    roi.zbegin = 0;
    roi.zend   = 1;
    if (!src.roi().contains(roi) || !radius.roi().contains(roi.xbegin, roi.ybegin)
        || !radius.roi().contains(roi.xend - 1, roi.yend - 1)) {
        dst.errorfmt("spread: the region {} is not inside both the image {} and the radius {}",
                     roi, src.roi(), radius.roi());
        return in;
    }
    in.roi = roi;
    in.nchannels = src.nchannels();
    in.pixels = FloatPixels(src, roi);
    in.radii = FloatPixels(radius, ROI(roi.xbegin, roi.xend, roi.ybegin,
                                       roi.yend, 0, 1, 0, 1));
    in.max_radius = max_radius(dst, in.pixels, in.radii, nthreads);
    in.valid = in.max_radius >= 0.0;
    return in;
}

ImageSpec output_spec(const OIIO::ImageBuf& src, const ROI& window)
{
    ImageSpec spec(window, OIIO::TypeFloat);
    spec.nchannels = src.nchannels();
    spec.channelnames = src.spec().channelnames;
    spec.alpha_channel = src.spec().alpha_channel;
    spec.full_x = src.spec().full_x;
    spec.full_y = src.spec().full_y;
    spec.full_width = src.spec().full_width;
    spec.full_height = src.spec().full_height;
    return spec;
}

namespace {

/// Writes spread rows into a float image of `nchannels`, every pixel.
class StoreRows final : public RowSink {
public:
    StoreRows(OIIO::ImageBuf& dst, int nchannels) : m_dst(dst), m_nchannels(nchannels) {}
    void row(int y, int x_begin, int x_end, const double* rgba) override
    {
        float* out = static_cast<float*>(m_dst.pixeladdr(x_begin, y));
        for (int x = x_begin; x < x_end; ++x, rgba += 4, out += m_nchannels)
            for (int c = 0; c < m_nchannels; ++c)
                out[c] = float(rgba[c]);
    }
    void dark(int y, int x_begin, int x_end) override
    {
        float* out = static_cast<float*>(m_dst.pixeladdr(x_begin, y));
        std::fill(out, out + size_t(x_end - x_begin) * m_nchannels, 0.0f);
    }

private:
    OIIO::ImageBuf& m_dst;
    int m_nchannels;
};

/// A non-owning handle: the profile outlives the filter call.
std::shared_ptr<const RowProfile> borrow(const RowProfile& profile)
{
    return std::shared_ptr<const RowProfile>(std::shared_ptr<const RowProfile>(), &profile);
}

}  // namespace

bool spread_image(OIIO::ImageBuf& dst, const OIIO::ImageBuf& src, const OIIO::ImageBuf& radius,
                  ROI roi, int nthreads, SpreadMethod method, const RowProfile* shape,
                  const HighlightTest& highlights, const CatEye& cateye, double box_aspect)
{
    const SpreadInputs in = prepare_spread(dst, src, radius, roi, nthreads);
    if (!in.valid)
        return false;
    const int nc = in.nchannels;
    if (nc > 4) {
        dst.errorfmt("spread: {} channels; at most 4 are spread at once", nc);
        return false;
    }
    roi = in.roi;
    // The engine reads RGBA: fewer channels are padded with zeros.
    std::vector<float> padded;
    const float* color = in.pixels(roi.xbegin, roi.ybegin);
    if (nc < 4) {
        padded.assign(size_t(roi.npixels()) * 4, 0.0f);
        for (size_t i = 0; i < size_t(roi.npixels()); ++i)
            std::copy(color + i * nc, color + i * nc + nc, &padded[i * 4]);
        color = padded.data();
    }
    SpreadSource source;
    source.roi = roi;
    source.color = color;
    source.radius = in.radii(roi.xbegin, roi.ybegin);
    source.box_aspect = box_aspect;
    source.cateye_side = cateye.side;
    std::vector<uint8_t> visible;
    if (highlights.threshold > 0.0 && in.max_radius >= smallest_merged_radius()) {
        auto view = [&](int nchannels, const float* pixels) {
            ImageSpec spec(roi.width(), roi.height(), nchannels, OIIO::TypeFloat);
            spec.x = roi.xbegin;
            spec.y = roi.ybegin;
            return OIIO::ImageBuf(spec, const_cast<float*>(pixels));
        };
        visible = visible_bokeh(view(4, color), view(1, source.radius), highlights, nthreads);
        add_pixels_alone(source, visible, nthreads);
        source.keep_exact = visible.data();
    }
    std::unique_ptr<ShapePrograms> programs;
    if (shape)
        programs = std::make_unique<ShapePrograms>(borrow(*shape), in.max_radius, cateye);
    const SpreadEngine engine(source, method, programs.get(), nthreads);
    // The engine hands on every pixel of its extent.
    reset_for_overwrite(dst, output_spec(src, engine.extent()), nthreads);
    StoreRows rows(dst, nc);
    engine.run(engine.extent(), rows, nthreads);
    return true;
}

}  // namespace defocus
