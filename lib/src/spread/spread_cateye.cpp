#include <defocus/spread/cateye.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "spread/scatter_pixels.h"

namespace defocus {

using Imath::V2d;
using OIIO::ImageBuf;
using OIIO::ROI;

namespace {

/// Sub-rows per footprint row: odd, so that sub-rows tile pixel rows.
constexpr int sub_rows = 3;

/// Fine enough for radii up to 32 x 2^6 = 2048 pixels; the cells' offsets
/// then stay within 16 bits (see ShapePrograms::clipped_blocks).
constexpr int max_cateye_fineness = 6;

/// The shape's sub-row spans at one radius, kept while neighbours share
/// it (a layer's radius mostly changes slowly).
struct SpanCache {
    const RowProfile* profile = nullptr;
    double radius = -1.0;
    std::vector<RowSpan> spans;

    const std::vector<RowSpan>& at(const RowProfile& p, double r)
    {
        if (&p != profile || r != radius) {
            p.rows(sub_rows * r, spans);
            profile = &p;
            radius = r;
        }
        return spans;
    }
};

/// Half the chord at height dy from its centre of the clip of CoC radius
/// r: the disc of radius r squeezed `clip_aspect` times as wide as tall,
/// keeping its area; negative where the row misses it.
double clip_half_chord(double r, double dy, double clip_aspect)
{
    const double width = std::sqrt(clip_aspect);
    const double t = dy * width / r;  // over the half-height r / width
    return std::abs(t) >= 1.0 ? -1.0 : r * width * std::sqrt(1.0 - t * t);
}

/// The sub-row spans `sub` of a shape (its spans at sub_rows times the
/// radius r) as spans of the footprint's rows, each cut by the clip of
/// radius r (clip_half_chord) centred at d when `clip` (unclipped if the
/// clip leaves nothing). Returns their area.
double clip_sub_rows(const std::vector<RowSpan>& sub, double r, bool clip, const V2d& d,
                     double clip_aspect, std::vector<RowSpan>& out)
{
    double area = 0.0;
    for (const bool clipping : { clip, false }) {
        out.clear();
        area = 0.0;
        for (const RowSpan& s : sub) {
            const double y = double(s.row) / sub_rows;  // the sub-row's middle
            double left = s.left / sub_rows, right = s.right / sub_rows;
            if (clipping) {
                const double h = clip_half_chord(r, y - d.y, clip_aspect);
                if (h < 0.0)
                    continue;
                left = std::max(left, d.x - h);
                right = std::min(right, d.x + h);
                if (right <= left)
                    continue;
            }
            const double weight = s.weight / sub_rows;
            out.push_back({ int(std::floor(y + 0.5)), left, right, weight });
            area += (right - left) * weight;
        }
        if (area > 0.0)
            break;
    }
    return area;
}

/// The intervals of the shape of a pixel centred at `at` with CoC radius r,
/// clipped by the cat's eye, normalised to total weight 1.
void clipped_intervals(const RowProfile& profile, const CatEye& cateye, const V2d& at, double r,
                       SpanCache& cache, std::vector<RowSpan>& out)
{
    const bool clip = cateye.amount > 0.0 && r >= cateye_min_radius;
    const V2d d = clip ? cateye.offset(at, r) : V2d(0.0, 0.0);
    const double area = clip_sub_rows(cache.at(profile, r), r, clip, d, cateye.clip_aspect, out);
    for (RowSpan& i : out)
        i.weight /= area;
}

/// Adds w times the coverage of [a, b] (pixel i covering [i, i + 1]) to a
/// row of deltas: two taps at each end.
void add_interval(double* row, int nc, double a, double b, const float* v, double w)
{
    const double fa = std::floor(a), fb = std::floor(b);
    const int ia = int(fa), ib = int(fb);
    const double taps[4] = { w * (1.0 - (a - fa)), w * (a - fa), -w * (1.0 - (b - fb)),
                             -w * (b - fb) };
    const int at[4] = { ia, ia + 1, ib, ib + 1 };
    for (int t = 0; t < 4; ++t)
        for (int c = 0; c < nc; ++c)
            row[ptrdiff_t(at[t]) * nc + c] += taps[t] * v[c];
}

}  // namespace

int cateye_fineness(int block, double r)
{
    // The edge's error is at most r times half a step, r / 64 at
    // fineness 0. Blocks take radii under 16 times their width.
    if (block > 1)
        return 0;
    int fineness = 0;
    while (fineness < max_cateye_fineness && r > 32.0 * (1 << fineness))
        ++fineness;
    return fineness;
}

CatEyeCell cateye_cell(const CatEye& cateye, const V2d& at, int fineness)
{
    // Cells centred on the grid's points, so that the optical centre's
    // cell is not clipped off-centre.
    const V2d u = cateye.offset(at, 1.0) * (std::ldexp(1.0, fineness) / cateye_cell_size);
    return { int(std::lround(u.x)), int(std::lround(u.y)), fineness };
}

V2d cateye_cell_offset(const CatEyeCell& cell)
{
    return V2d(cell.x, cell.y) * std::ldexp(cateye_cell_size, -cell.fineness);
}

ClippedProfile::ClippedProfile(std::shared_ptr<const RowProfile> aperture,
                               const V2d& offset_per_radius, double clip_aspect, bool clip)
    : m_aperture(std::move(aperture))
    , m_offset(offset_per_radius)
    , m_clip_aspect(clip_aspect)
    , m_clip(clip)
{
}

double ClippedProfile::rows(double r, std::vector<RowSpan>& spans) const
{
    std::vector<RowSpan> sub;
    m_aperture->rows(sub_rows * r, sub);
    return clip_sub_rows(sub, r, m_clip && r >= cateye_min_radius, m_offset * r, m_clip_aspect,
                         spans);
}

bool spread_cateye(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius,
                   const RowProfile& profile, const CatEye& cateye, ROI roi, int nthreads)
{
    return scatter_pixels(
        dst, src, radius, roi, nthreads,
        [&](double max_radius) {
            const int reach = int(std::ceil(max_radius * profile.extent())) + 2;
            return PixelReach { -reach, reach, -reach, reach };
        },
        true,
        [&](int x, int y, const float* v, int nc, double r, auto&& row) {
            thread_local SpanCache spans;
            thread_local std::vector<RowSpan> intervals;
            clipped_intervals(profile, cateye, V2d(x + 0.5, y + 0.5), r, spans, intervals);
            for (const RowSpan& i : intervals)
                if (double* out = row(y + i.row))
                    add_interval(out, nc, x + 0.5 + i.left, x + 0.5 + i.right, v, i.weight);
        });
}

bool spread_cateye(ImageBuf& dst, const ImageBuf& src, const ImageBuf& radius, const Psf& psf,
                   const CatEye& cateye, ROI roi, int nthreads)
{
    // Clipping only drops weights: the unclipped footprints bound the reach.
    return scatter_pixels(
        dst, src, radius, roi, nthreads,
        [&](double max_radius) { return footprint_reach(psf, max_radius); }, false,
        [&](int x, int y, const float* v, int nc, double r, auto&& row) {
            Footprint fp = psf(r);
            if (cateye.amount > 0.0 && r >= cateye_min_radius) {
                const V2d d = cateye.offset(V2d(x + 0.5, y + 0.5), r);
                double kept = 0.0, all = 0.0;
                for (int j = 0; j < fp.height; ++j)
                    for (int i = 0; i < fp.width; ++i) {
                        double& w = fp.weights[size_t(j) * fp.width + i];
                        all += w;
                        const double h = clip_half_chord(r, fp.y0 + j - d.y, cateye.clip_aspect);
                        if (std::abs(fp.x0 + i - d.x) > h)
                            w = 0.0;
                        kept += w;
                    }
                if (kept > 0.0)
                    for (double& w : fp.weights)
                        w *= all / kept;
                else
                    fp = psf(r);  // the clip missed every sample: unclipped
            }
            add_footprint(fp, x, y, v, nc, row);
        });
}

Footprint cateye_footprint(const RowProfile& profile, const CatEye& cateye, const V2d& at,
                           double r)
{
    SpanCache spans;
    std::vector<RowSpan> intervals;
    clipped_intervals(profile, cateye, at, r, spans, intervals);
    // Offsets from the pixel at `at`, whose own column spans [0, 1) here.
    const double x = at.x - std::floor(at.x);
    int first = 0, last = 0, left = 0, right = 0;
    for (const RowSpan& i : intervals) {
        first = std::min(first, i.row);
        last = std::max(last, i.row);
        left = std::min(left, int(std::floor(x + i.left)));
        right = std::max(right, int(std::floor(x + i.right)));
    }
    Footprint fp;
    fp.x0 = left;
    fp.y0 = first;
    fp.width = right - left + 1;
    fp.height = last - first + 1;
    fp.weights.assign(size_t(fp.width) * fp.height, 0.0);
    for (const RowSpan& i : intervals)
        for (int c = left; c <= right; ++c) {
            const double overlap = std::min(double(c + 1), x + i.right)
                                   - std::max(double(c), x + i.left);
            if (overlap > 0.0)
                fp.weights[size_t(i.row - first) * fp.width + (c - left)] += overlap * i.weight;
        }
    return fp;
}

}  // namespace defocus
