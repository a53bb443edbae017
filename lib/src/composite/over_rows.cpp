#include "composite/over_rows.h"

#include <cmath>
#include <vector>

#include <OpenImageIO/parallel.h>

#include "composite/magnified_axis.h"
#include "util/float_pixels.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

/// "Over" (see Over) of n spread pixels onto the frame's, in the channels
/// `written`; `onto_black`: the frame's pixels count as black; `change`,
/// when given, is added to each (see composited()).
DEFOCUS_CLONES
void composite_over(float* out, const double* rgba, int n, const Lanes& written,
                    bool onto_black, const float* change)
{
    for (int x = 0; x < n; ++x, rgba += 4, out += 4) {
        const d4 spread = composited(load4(rgba), change ? change + x * 4 : nullptr);
        const double alpha = spread[3];
        const d4 under = onto_black ? splat(0.0) : load4(out);
        store4(out, d4 { written ? (spread + splat(1.0 - alpha) * under).v : under.v });
    }
}

/// Composites colour channel `c` of a layer's spread (RGBA) over the frame
/// magnified by `m` about `centre` (lateral chromatic aberration): the
/// light of each spread pixel lands m times as far from the centre, split
/// bilinearly over the four pixels around where it lands, so that the
/// channel keeps its light and its centroid exactly. Alpha is coverage, not
/// light: the frame samples it bilinearly where each pixel came from.
void composite_magnified(ImageBuf& frame, const ImageBuf& spread, int c, double m,
                         const Imath::V2d& centre, int nthreads)
{
    ChannelPass pass { CocChannel::Green, { false, false, false }, false };
    pass.colour[c] = true;
    Over over(frame, pass, false);
    const ROI in = spread.roi();
    // Beyond the spread's reach, "over" of nothing leaves the frame as it is.
    const auto [x_begin, x_end] = MagnifiedAxis::reached(in.xbegin, in.xend, m, centre.x);
    const auto [y_begin, y_end] = MagnifiedAxis::reached(in.ybegin, in.yend, m, centre.y);
    const ROI out = roi_intersection(frame.roi(), ROI(x_begin, x_end, y_begin, y_end, 0, 1, 0, 4));
    if (out.npixels() <= 0)
        return;
    const FloatPixels pixels(spread, in);
    // Rows of the spread by index, null outside it, where everything is 0.
    auto row_at = [&](int y) {
        return y < in.ybegin || y >= in.yend ? nullptr : pixels(in.xbegin, y);
    };
    const int stride = pixels.nchannels();
    auto at = [&](const float* r, int x, int ch) {
        return r && x >= in.xbegin && x < in.xend ? double(r[(x - in.xbegin) * stride + ch])
                                                  : 0.0;
    };
    const MagnifiedAxis columns(out.xbegin, out.xend, m, centre.x),
                        rows(out.ybegin, out.yend, m, centre.y);
    parallel_for(out.ybegin, out.yend, [&](int y) {
        std::vector<double> row(size_t(out.width()) * 4, 0.0);
        const MagnifiedAxis::Pixel& ry = rows[y];
        const float *r0 = row_at(ry.from), *r1 = row_at(ry.from + 1);
        std::vector<const float*> sources;
        for (int ky = 0; ky < ry.sources; ++ky)
            sources.push_back(row_at(ry.first_source + ky));
        const bool rows_inside =
            r0 && r1 && std::find(sources.begin(), sources.end(), nullptr) == sources.end();
        const double fy = ry.fraction;
        // `checked`: some of the pixel's sources may lie outside the spread.
        auto magnify = [&](int x, auto checked) {
            auto value = [&](const float* r, int sx, int ch) {
                if constexpr (decltype(checked)::value)
                    return at(r, sx, ch);
                else
                    return double(r[(sx - in.xbegin) * stride + ch]);
            };
            const MagnifiedAxis::Pixel& rx = columns[x];
            const int x0 = rx.from;
            const double fx = rx.fraction;
            double* p = &row[size_t(x - out.xbegin) * 4];
            p[3] = (1 - fy) * ((1 - fx) * value(r0, x0, 3) + fx * value(r0, x0 + 1, 3))
                   + fy * ((1 - fx) * value(r1, x0, 3) + fx * value(r1, x0 + 1, 3));
            double light = 0.0;
            for (int ky = 0; ky < ry.sources; ++ky) {
                const double wy = rows.weight(ry, ky);
                for (int kx = 0; kx < rx.sources && wy > 0.0; ++kx) {
                    const double wx = columns.weight(rx, kx);
                    if (wx > 0.0)
                        light += wx * wy * value(sources[size_t(ky)], rx.first_source + kx, c);
                }
            }
            p[c] = light;
        };
        for (int x = out.xbegin; x < out.xend; ++x) {
            const MagnifiedAxis::Pixel& rx = columns[x];
            const bool inside = rows_inside && rx.from >= in.xbegin && rx.from + 1 < in.xend
                                && rx.first_source >= in.xbegin
                                && rx.first_source + rx.sources <= in.xend;
            if (inside)
                magnify(x, std::false_type());
            else
                magnify(x, std::true_type());
        }
        over.row(y, out.xbegin, out.xend, row.data());
    }, by_rows(nthreads));
}

/// Composites a layer spread apart over the frame, within the frame's
/// window, in the channels of `pass`, with its changes in `cells` (when
/// given).
void composite_image(ImageBuf& frame, const ImageBuf& layer, const ChannelPass& pass,
                     const SubApertureLayers* cells, size_t index, int nthreads)
{
    const ROI both = roi_intersection(frame.roi(), layer.roi());
    Over over(frame, pass, false, cells, index);
    if (both.width() <= 0)
        return;
    parallel_for(both.ybegin, both.yend, [&](int y) {
        over.float_row(y, both.xbegin, both.xend,
                       static_cast<const float*>(layer.pixeladdr(both.xbegin, y)),
                       layer.nchannels());
    }, by_rows(nthreads));
}

/// Puts layer `index`'s changes in `cells` into its spread (float RGBA)
/// where it has any, each such pixel as "over" composites it
/// (composited()): a pass whose red and blue are composited magnified
/// from its spread takes them so.
void add_changes(ImageBuf& spread, const SubApertureLayers& cells, size_t index, int nthreads)
{
    const ROI roi = spread.roi();
    const int stride = spread.nchannels();
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        cells.each_run(index, y, roi.xbegin, roi.xend, [&](int x, int end, const float* change) {
            if (!change)
                return;
            float* pixel = static_cast<float*>(spread.pixeladdr(x, y));
            for (int i = 0; i < end - x; ++i, pixel += stride)
                store4(pixel, composited(load4(pixel), change + i * 4));
        });
    }, by_rows(nthreads));
}

}  // namespace defocus
