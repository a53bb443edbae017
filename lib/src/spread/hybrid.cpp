#include <defocus/spread/hybrid.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/parallel.h>

#include "util/float_pixels.h"
#include "util/parallel_rows.h"
#include "util/prefault.h"

namespace defocus {

using namespace OIIO;

namespace {

double luminance(const float* c, const Imath::V3d& luma)
{
    return luma.x * c[0] + luma.y * c[1] + luma.z * c[2];
}

}  // namespace

bool PsfImage::set_image(const ImageBuf& image, const Imath::V3d& luma, std::string& error)
{
    const ROI roi = image.roi();
    const int nc = image.nchannels();
    m_width = roi.width();
    m_height = roi.height();
    m_luma.assign(size_t(m_width) * m_height, 0.0f);
    double total = 0.0;
    for (int y = 0; y < m_height; ++y)
        for (int x = 0; x < m_width; ++x) {
            float c[4] = { 0, 0, 0, 0 };
            image.getpixel(roi.xbegin + x, roi.ybegin + y, c, std::min(nc, 4));
            const double l = nc >= 3 ? luminance(c, luma) : c[0];
            if (!(l >= 0.0) || !std::isfinite(l)) {
                error = "the PSF image has negative or non-finite values";
                return false;
            }
            m_luma[size_t(y) * m_width + x] = float(l);
            total += l;
        }
    if (!(total > 0.0)) {
        error = "the PSF image is black";
        return false;
    }
    return true;
}

float PsfImage::sample(double u, double v) const
{
    // Pixel centres at (i + 0.5) / width; zero outside the image.
    const double x = u * m_width - 0.5, y = v * m_height - 0.5;
    const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    auto at = [&](int i, int j) {
        return i >= 0 && j >= 0 && i < m_width && j < m_height
                   ? double(m_luma[size_t(j) * m_width + i]) : 0.0;
    };
    return float((1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0))
                 + fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1)));
}

Footprint PsfImage::footprint(double r) const
{
    Footprint fp;
    if (r < 1.0) {
        fp.width = fp.height = 1;
        fp.weights = { 1.0 };
        return fp;
    }
    const int reach = int(std::ceil(r));
    fp.x0 = fp.y0 = -reach;
    fp.width = fp.height = 2 * reach + 1;
    fp.weights.resize(size_t(fp.width) * fp.height);
    double total = 0.0;
    for (int j = 0; j < fp.height; ++j)
        for (int i = 0; i < fp.width; ++i) {
            const double u = 0.5 + (fp.x0 + i) / (2.0 * r);
            const double v = 0.5 + (fp.y0 + j) / (2.0 * r);
            const double w = sample(u, v);
            fp.weights[size_t(j) * fp.width + i] = w;
            total += w;
        }
    if (total <= 0.0) {  // a PSF too fine to sample at this size
        std::fill(fp.weights.begin(), fp.weights.end(), 0.0);
        fp.weights[size_t(reach) * fp.width + reach] = 1.0;
        return fp;
    }
    for (double& w : fp.weights)
        w /= total;
    return fp;
}

std::vector<uint8_t> visible_bokeh(const ImageBuf& color, const ImageBuf& radius,
                                   const HighlightTest& test, int nthreads)
{
    const ROI roi = color.roi();
    const int w = roi.width(), h = roi.height();
    const FloatPixels pixels(color, roi);
    const FloatPixels radii(radius, ROI(roi.xbegin, roi.xend, roi.ybegin, roi.yend, 0, 1, 0, 1));
    // Summed-area table of luminance, one row and column of zeros in front:
    // each row's running sums in parallel, then down the columns in bands.
    // Not zero-filled on allocation: the passes below write every entry,
    // in parallel, which also spreads the fresh pages' faults over threads.
    const std::unique_ptr<double[]> sat(new double[size_t(w + 1) * (h + 1)]);
    prefault(sat.get(), sizeof(double) * size_t(w + 1) * (h + 1), nthreads);
    std::fill(&sat[0], &sat[0] + w + 1, 0.0);
    parallel_for(0, h, [&](int y) {
        double* row = &sat[size_t(y + 1) * (w + 1)];
        *row++ = 0.0;
        const float* c = pixels(roi.xbegin, roi.ybegin + y);
        double sum = 0.0;
        for (int x = 0; x < w; ++x, c += pixels.nchannels())
            row[x] = sum += luminance(c, test.luma);
    }, by_rows(nthreads));
    parallel_for_chunked(0, w + 1, 0, [&](int64_t x0, int64_t x1) {
        for (int y = 1; y <= h; ++y) {
            double* row = &sat[size_t(y) * (w + 1)];
            const double* above = row - (w + 1);
            for (int64_t x = x0; x < x1; ++x)
                row[x] += above[x];
        }
    }, by_rows(nthreads));
    std::vector<uint8_t> selected(size_t(w) * h, 0);
    parallel_for(0, h, [&](int y) {
        // Locals, not the captures: a store through a byte pointer may
        // alias anything, so captured values would be reloaded every pixel.
        const double* table = sat.get();
        const double contrast = test.threshold;
        const Imath::V3d luma = test.luma;
        const int channels = pixels.nchannels();
        uint8_t* out = selected.data() + size_t(y) * w;
        const float* c = pixels(roi.xbegin, roi.ybegin + y);
        const float* r = radii(roi.xbegin, roi.ybegin + y);
        for (int x = 0; x < w; ++x, c += channels) {
            const double l = luminance(c, luma);
            if (r[x] < 1.0f || l <= 0.0)
                continue;
            const int k = int(std::ceil(r[x]));
            const int x0 = std::max(0, x - k), x1 = std::min(w, x + k + 1);
            const int y0 = std::max(0, y - k), y1 = std::min(h, y + k + 1);
            const double sum = table[size_t(y1) * (w + 1) + x1] - table[size_t(y0) * (w + 1) + x1]
                               - table[size_t(y1) * (w + 1) + x0] + table[size_t(y0) * (w + 1) + x0];
            const double mean = sum / (double(x1 - x0) * (y1 - y0));
            out[x] = l > contrast * mean;
        }
    }, by_rows(nthreads));
    return selected;
}

}  // namespace defocus
