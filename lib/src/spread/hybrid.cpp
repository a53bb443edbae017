#include <defocus/spread/hybrid.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/parallel.h>

#include "util/float_pixels.h"
#include "util/parallel_rows.h"
#include "util/simd.h"

namespace defocus {

using namespace OIIO;

namespace {

DEFOCUS_KERNEL double luminance(const float* c, const Imath::V3d& luma)
{
    return luma.x * c[0] + luma.y * c[1] + luma.z * c[2];
}

/// The luminance of a row of w pixels of `channels` floats each.
template<typename Channels>
DEFOCUS_KERNEL void luminance_row(const float* c, Channels channels, int w,
                                  const Imath::V3d& luma, double* out)
{
    for (int x = 0; x < w; ++x)
        out[x] = luminance(c + x * channels, luma);
}

DEFOCUS_CLONES
void luminance_row(const float* c, int channels, int w, const Imath::V3d& luma, double* out)
{
    // RGBA mostly: a constant stride vectorises.
    if (channels == 4)
        luminance_row(c, std::integral_constant<int, 4>(), w, luma, out);
    else
        luminance_row(c, channels, w, luma, out);
}

/// The boundaries below N consecutive rows of luminance `l[0..N)` in a
/// summed-area table, from the boundary above the first. Each row's
/// running sum is a chain of dependent additions; N rows side by side keep
/// the adders busy, with each sum made in the same order as row by row.
template<int N>
DEFOCUS_KERNEL void next_boundaries(const double* above, const double* const* l, int w,
                                    double* const* below)
{
    double sum[N];
    for (int j = 0; j < N; ++j) {
        sum[j] = 0.0;
        below[j][0] = 0.0;
    }
    for (int x = 0; x < w; ++x) {
        double boundary = above[x + 1];
        for (int j = 0; j < N; ++j) {
            sum[j] += l[j][x];
            boundary += sum[j];
            below[j][x + 1] = boundary;
        }
    }
}

DEFOCUS_CLONES
void next_boundaries(const double* above, const double* const* l, int n, int w,
                     double* const* below)
{
    switch (n) {
    case 1: next_boundaries<1>(above, l, w, below); break;
    case 2: next_boundaries<2>(above, l, w, below); break;
    case 3: next_boundaries<3>(above, l, w, below); break;
    default: next_boundaries<4>(above, l, w, below); break;
    }
}

/// The rows of a summed-area table a pixel's window spans: k rows above
/// and k below it, by k = ceil(CoC radius) up to the layer's reach.
struct WindowRows {
    const double* const* top;     ///< the boundaries above the windows
    const double* const* bottom;  ///< the boundaries below them
    int reach;
    int y, height;                ///< the row tested, of the layer's
};

/// The verdicts of one row (see visible_bokeh) of w pixels of luminance
/// `l` and CoC radius `r`: 1 where l exceeds `contrast` times the mean
/// over the window. Comparisons without a division, the sums as
/// differences of boundaries.
DEFOCUS_CLONES
void test_row(const double* l, const float* r, int w, const WindowRows& rows, double contrast,
              uint8_t* out)
{
    // The boundaries of windows k rows up and down: those of the reach
    // for larger ones, as reach <= height and they span every row too.
    auto up_to_reach = [&](int k) { return std::min(rows.reach, k); };
    auto rows_spanned = [&](int k) {
        return std::min(rows.height, rows.y + k + 1) - std::max(0, rows.y - k);
    };
    constexpr int lanes = 8;
    int x = 0;
    while (x < w) {
        // Pixels `lanes` at a time where their windows are one size and
        // lie within the row: one vector of sums from four rows' stretches.
        const int k = r[x] >= 1.0f ? int(std::ceil(r[x])) : 0;
        bool same = k > 0 && x - k >= 0 && x + lanes + k <= w;
        for (int j = 1; same && j < lanes; ++j)
            same = r[x + j] >= 1.0f && int(std::ceil(r[x + j])) == k;
        if (same) {
            const double* top = rows.top[up_to_reach(k)];
            const double* bottom = rows.bottom[up_to_reach(k)];
            const double area = double(2 * k + 1) * rows_spanned(k);
            // Verdicts stored together: a byte stored alone may alias
            // the table, which the next lane would then have to reload.
            uint8_t verdicts[lanes];
            for (int j = 0; j < lanes; ++j) {
                const int x0 = x + j - k, x1 = x + j + k + 1;
                const double sum = bottom[x1] - top[x1] - bottom[x0] + top[x0];
                verdicts[j] = (l[x + j] > 0.0) & (l[x + j] * area > contrast * sum);
            }
            std::memcpy(out + x, verdicts, lanes);
            x += lanes;
            continue;
        }
        if (r[x] >= 1.0f && l[x] > 0.0) {
            const int x0 = std::max(0, x - k), x1 = std::min(w, x + k + 1);
            const double* top = rows.top[up_to_reach(k)];
            const double* bottom = rows.bottom[up_to_reach(k)];
            const double sum = bottom[x1] - top[x1] - bottom[x0] + top[x0];
            out[x] = l[x] * (double(x1 - x0) * rows_spanned(k)) > contrast * sum;
        }
        ++x;
    }
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
    std::vector<uint8_t> selected(size_t(w) * h, 0);
    if (w <= 0 || h <= 0)
        return selected;
    // How far any window reaches from its row: the largest radius of a
    // pixel that is tested.
    std::vector<float> row_largest(h, 0.0f);
    parallel_for(0, h, [&](int y) {
        const Imath::V3d luma = test.luma;
        const float* c = pixels(roi.xbegin, roi.ybegin + y);
        const float* r = radii(roi.xbegin, roi.ybegin + y);
        float largest = 0.0f;
        for (int x = 0; x < w; ++x, c += pixels.nchannels())
            if (r[x] > largest && luminance(c, luma) > 0.0)
                largest = r[x];
        row_largest[y] = largest;
    }, by_rows(nthreads));
    const float largest = *std::max_element(row_largest.begin(), row_largest.end());
    const int reach = std::min(h, int(std::ceil(largest)));
    // Each band of rows keeps a summed-area table of luminance of only the
    // rows its windows reach (the boundaries above rows y - reach ..
    // y + reach + 1, in a ring), relative to its first row: a window's sum
    // is a difference of boundaries, whatever they are relative to. The
    // ring stays in cache, so the pixels are read from memory about once,
    // where a table of the whole layer would be written and read again.
    // Rows are summed up to `batch` at a time, ahead of the row tested.
    constexpr int batch = 4;
    const int ring = std::min(h + 1, 2 * reach + 1 + batch);
    paropt threads = by_rows(nthreads);
    threads.resolve();
    // Bands of at least a few reaches, so that the rows summed twice (by
    // two bands) stay few.
    const int bands = std::max(1, std::min(4 * threads.maxthreads(), h / std::max(1, 4 * reach)));
    const int band_rows = (h + bands - 1) / bands;
    parallel_for_each_item(0, bands, [&](int64_t band) {
        const int y_begin = band * band_rows, y_end = std::min(h, y_begin + band_rows);
        std::vector<double> table(size_t(ring) * (w + 1));
        auto boundary = [&](int j) { return table.data() + size_t(j % ring) * (w + 1); };
        // The luminance of the rows summed and not yet tested: rows y to
        // y + reach, and those summed ahead.
        const int kept = reach + batch;
        std::vector<double> luminances(size_t(kept) * w);
        auto luminance_of = [&](int j) { return luminances.data() + size_t(j % kept) * w; };
        // The boundaries k rows above and k + 1 below the row tested, by k.
        std::vector<const double*> tops(size_t(reach) + 1), bottoms(size_t(reach) + 1);
        // The boundaries up to `made` are in the ring.
        int made = std::max(0, y_begin - reach);
        std::fill(boundary(made), boundary(made) + w + 1, 0.0);
        for (int y = y_begin; y < y_end; ++y) {
            while (made < std::min(h, y + reach + 1)) {
                const int n = std::min(batch, h - made);
                const double* rows[batch];
                double* below[batch];
                for (int j = 0; j < n; ++j) {
                    luminance_row(pixels(roi.xbegin, roi.ybegin + made + j), pixels.nchannels(),
                                  w, test.luma, luminance_of(made + j));
                    rows[j] = luminance_of(made + j);
                    below[j] = boundary(made + j + 1);
                }
                next_boundaries(boundary(made), rows, n, w, below);
                made += n;
            }
            for (int k = 0; k <= reach; ++k) {
                tops[k] = boundary(std::max(0, y - k));
                bottoms[k] = boundary(std::min(h, y + k + 1));
            }
            test_row(luminance_of(y), radii(roi.xbegin, roi.ybegin + y), w,
                     { tops.data(), bottoms.data(), reach, y, h }, test.threshold,
                     selected.data() + size_t(y) * w);
        }
    }, nthreads);
    return selected;
}

}  // namespace defocus
