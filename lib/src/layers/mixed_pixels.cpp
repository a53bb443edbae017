#include <defocus/layers/mixed_pixels.h>

#include <algorithm>
#include <cmath>

#include <OpenImageIO/parallel.h>

#include "layers/blur_field.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// How far around a mixed pixel its sides' colours are taken from: an
/// antialiased rim is a pixel or two wide, and the unmixed pixels beyond
/// it are within three.
constexpr int reach = 3;

/// Sums over the pixels of one side of a discontinuity.
struct Side {
    double rgba[4] = { 0, 0, 0, 0 };
    double z = 0;
    int count = 0;

    void add(const float* color, float depth)
    {
        for (int i = 0; i < 4; ++i)
            rgba[i] += color[i];
        z += depth;
        ++count;
    }
    double mean(int i) const { return rgba[i] / count; }
    double mean_depth() const { return z / count; }
};

/// Where `color` projects on the line from `far` to `near`: 0 at far, 1 at
/// near (unclamped), and the line's squared length.
struct Projection {
    double along, length;

    Projection(const float* color, const double near[3], const float* far)
        : along(0.0), length(0.0)
    {
        for (int i = 0; i < 3; ++i) {
            const double d = near[i] - far[i];
            along += (color[i] - far[i]) * d;
            length += d * d;
        }
    }
    double t() const { return length > 0.0 ? std::clamp(along / length, 0.0, 1.0) : 0.0; }
};

/// How far `color` lies from the nearest blend of `near` and `far`,
/// relative to its own level (squared).
double blend_error(const float* color, const double near[3], const float* far)
{
    const double t = Projection(color, near, far).t();
    double error = 0.0, level = 1e-12;
    for (int i = 0; i < 3; ++i) {
        const double e = color[i] - (far[i] + t * (near[i] - far[i]));
        error += e * e;
        level += double(color[i]) * color[i];
    }
    return error / level;
}

/// A pixel of the neighbourhood.
struct Where {
    int x, y;
};

/// The pixels within `reach` of a mixed pixel, each on the near or the
/// far side of the CoC midway between the pixel's own and the other
/// side's.
struct Neighbourhood {
    const BlurField& field;
    int x, y;
    float middle;
    int x0, x1, y0, y1;

    Neighbourhood(const BlurField& field, int x, int y, float middle)
        : field(field), x(x), y(y), middle(middle)
    {
        const ROI& roi = field.roi();
        x0 = std::max(x - reach, roi.xbegin), x1 = std::min(x + reach, roi.xend - 1);
        y0 = std::max(y - reach, roi.ybegin), y1 = std::min(y + reach, roi.yend - 1);
    }

    /// visit(sx, sy, near) for each covered pixel but (x, y) itself.
    template<typename Visit>
    void each(Visit&& visit) const
    {
        for (int sy = y0; sy <= y1; ++sy)
            for (int sx = x0; sx <= x1; ++sx) {
                const float c = field.blur(sx, sy);
                if (!std::isnan(c) && (sx != x || sy != y))
                    visit(sx, sy, c < middle);
            }
    }

    /// The far side's pixel with the least `cost(sx, sy)` of those
    /// `chosen(sx, sy)`; between equals, the first.
    template<typename Chosen, typename Cost>
    Where least_far(Chosen&& chosen, Cost&& cost) const
    {
        Where best { x, y };
        double least = INFINITY;
        each([&](int sx, int sy, bool is_near) {
            if (is_near || !chosen(sx, sy))
                return;
            const double c = cost(sx, sy);
            if (c < least) {
                least = c;
                best = { sx, sy };
            }
        });
        return best;
    }

    int distance2(int sx, int sy) const { return (sx - x) * (sx - x) + (sy - y) * (sy - y); }

    /// Chooses the far side's unmixed pixels, or its mixed ones when `mixed`.
    auto of_kind(bool mixed) const
    {
        return [this, mixed](int sx, int sy) { return field.at_discontinuity(sx, sy) == mixed; };
    }

    /// The far side's pixel (of its unmixed ones, or its mixed ones when
    /// `mixed`) which, blended with `near`, comes closest to the pixel's
    /// colour; between equals, the nearest. A far side of
    /// several colours (a light beside a wall, a checker) has a mean that
    /// explains no pixel (colour sampling for matting: Wang & Cohen,
    /// "Optimized Color Sampling for Robust Matting", CVPR 2007).
    Where best_explaining_far(const double near[3], bool mixed) const
    {
        const float* color = field.color(x, y);
        return least_far(of_kind(mixed), [&](int sx, int sy) {
            return blend_error(color, near, field.color(sx, sy)) + 1e-4 * distance2(sx, sy);
        });
    }

    /// The far side's nearest pixel (of its unmixed ones, or its mixed ones
    /// when `mixed`).
    Where nearest_far(bool mixed) const
    {
        return least_far(of_kind(mixed),
                         [&](int sx, int sy) { return double(distance2(sx, sy)); });
    }

    /// The far side's nearest pixel, mixed or not.
    Where nearest_far() const
    {
        return least_far([](int, int) { return true; },
                         [&](int sx, int sy) { return double(distance2(sx, sy)); });
    }
};

bool split(const BlurField& field, int x, int y, MixedPixel& out, Where* far_source = nullptr);

/// A pixel written at the near surface's depth and wholly covered by it,
/// with the far surface continued behind it as it is at its nearest pixel:
/// a deep render holds such a sample wherever an edge covers a pixel
/// partly. It changes nothing where the near surface is sharp; where it is
/// blurred, what shows through its edge starts from the far surface at the
/// edge, and the hidden-surface fill continues from there rather than from
/// whatever lies a pixel beyond (a far light beside a pole's edge, with
/// nothing else of the far surface along that edge, flooded the whole band
/// behind the pole).
bool continue_behind(const BlurField& field, const Neighbourhood& around, MixedPixel& out)
{
    const int x = around.x, y = around.y;
    const float* color = field.color(x, y);
    if (!(color[3] >= 0.999f))
        return false;
    // The nearest far pixel is often a blend of the two sides itself; its
    // split tells which pixel stands for its far side.
    Where far = around.nearest_far();
    if (MixedPixel ignored; field.at_discontinuity(far.x, far.y))
        split(field, far.x, far.y, ignored, &far);
    const float* behind = field.color(far.x, far.y);
    if (!(behind[3] > 0.0f))
        return false;
    out.x = x;
    out.y = y;
    std::copy(color, color + 4, out.near);
    std::copy(behind, behind + 4, out.far);
    out.near_z = field.depth(x, y);
    out.far_z = field.depth(far.x, far.y);
    out.far_continued = true;
    return true;
}

/// Pixel (x, y), mixed, as its two surfaces; false when it is better left
/// whole. Where `far_source` is given, a pixel written at the far depth
/// that splits sets it to the pixel whose colour stands for its far side,
/// and no far surface is continued.
bool split(const BlurField& field, int x, int y, MixedPixel& out, Where* far_source)
{
    const float own = field.blur(x, y);
    const float other = field.other_side(x, y);
    const bool written_near = own < other;
    const Neighbourhood around(field, x, y, 0.5f * (own + other));
    // The near side's colour is the mean of its unmixed pixels; a side only
    // a pixel or two wide (a wire, a small light) has none, and takes its
    // mixed ones. So does the far side's choice of pixels.
    Side sides[2][2];  // [near][mixed]
    around.each([&](int sx, int sy, bool is_near) {
        sides[is_near][field.at_discontinuity(sx, sy)].add(field.color(sx, sy),
                                                           field.depth(sx, sy));
    });
    const Side& near = sides[1][0].count ? sides[1][0] : sides[1][1];
    const bool far_mixed = sides[0][0].count == 0;
    if (near.count == 0 || sides[0][far_mixed].count == 0)
        return false;
    const double near_color[3] = { near.mean(0), near.mean(1), near.mean(2) };
    // Behind a pixel written at the near depth, the far surface continues
    // from its nearest pixel: the near side's mean stands for a textured
    // near surface badly, and a far colour chosen to explain the pixel
    // against it makes up a far surface (a dark checker behind a pole's
    // dark stripe).
    const Where far_pixel = written_near ? around.nearest_far(far_mixed)
                                         : around.best_explaining_far(near_color, far_mixed);
    const float* far = field.color(far_pixel.x, far_pixel.y);
    const float* color = field.color(x, y);
    auto whole = [&] { return written_near && !far_source && continue_behind(field, around, out); };

    // The pixel's colour as near·alpha + far·(1 - alpha): alpha is where its
    // colour projects on the line between the sides' colours.
    const Projection projection(color, near_color, far);
    double scale = 0.0;
    for (int i = 0; i < 3; ++i)
        scale += near_color[i] * near_color[i] + double(far[i]) * far[i];
    // Sides that differ by less than about 1% in colour look the same
    // wherever the pixel's light goes.
    if (!(projection.length > 1e-4 * scale) || !(far[3] > 0.0f))
        return whole();
    // A colour well beyond either side is not a blend of the two: the
    // near side's mean stands for a textured surface badly, and such a pixel
    // (a dark stripe beside a grey pole) is left whole.
    if (projection.along < -0.1 * projection.length || projection.along > 1.1 * projection.length)
        return whole();
    const double alpha = projection.t();
    // The far surface lies whole behind the near one, in its side's colour,
    // and is seen through what the near one leaves uncovered; the near
    // fragment takes the rest of the pixel's light. So no estimate is
    // divided by the uncovered part (near 0 at the silhouette's inner rim)
    // and the far side holds only the colour it has around the pixel.
    const double a = color[3];
    double covered = std::min(alpha * near.mean(3), a);
    // The far side's share takes no more of a channel than the pixel holds.
    for (int i = 0; i < 3; ++i)
        if (far[i] > 0.0f)
            covered = std::max(covered, a - color[i] * double(far[3]) / far[i]);
    const double behind = a - covered;  // the far side's share of coverage
    // Nothing of the near surface, or nothing of the far one: the pixel is
    // right as it is.
    if (!(covered > 1e-3 * a && behind > 1e-3 * a))
        return whole();
    const double through = 1.0 - covered;
    out.x = x;
    out.y = y;
    for (int i = 0; i < 3; ++i) {
        const double share = double(far[i]) / far[3] * behind;
        out.near[i] = float(std::max(0.0, color[i] - share));
        out.far[i] = through > 0.0 ? float(share / through) : 0.0f;
    }
    out.near[3] = float(covered);
    out.far[3] = through > 0.0 ? float(behind / through) : 0.0f;
    out.near_z = written_near ? field.depth(x, y) : float(near.mean_depth());
    out.far_z = field.depth(written_near ? far_pixel.x : x, written_near ? far_pixel.y : y);
    if (far_source && !written_near)
        *far_source = far_pixel;
    return true;
}

}  // namespace

std::vector<MixedPixel> find_mixed_pixels(const Layer& flat, const CircleOfConfusion& coc,
                                          int nthreads)
{
    return find_mixed_pixels(BlurField(flat, coc, nthreads), nthreads);
}

std::vector<MixedPixel> find_mixed_pixels(const BlurField& field, int nthreads)
{
    const ROI& roi = field.roi();
    std::vector<std::vector<MixedPixel>> rows(roi.height());
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x)
            if (MixedPixel pixel; field.at_discontinuity(x, y) && split(field, x, y, pixel))
                rows[y - roi.ybegin].push_back(pixel);
    }, by_rows(nthreads));
    std::vector<MixedPixel> all;
    for (const std::vector<MixedPixel>& row : rows)
        all.insert(all.end(), row.begin(), row.end());
    return all;
}

}  // namespace defocus
