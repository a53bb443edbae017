#include <defocus/spread/aperture_profile.h>

#include <algorithm>
#include <cmath>

#include <OpenImageIO/imagebuf.h>

#include "spread/footprint_program.h"

namespace defocus {

namespace {

constexpr double pi = 3.14159265358979323846;
constexpr double min_radius = 0.5;   // a disc inside its own pixel

/// The unit outline, as render cameras draw it: a disc of radius 1, or a
/// regular polygon inscribed in it (its vertices on the circle), turned
/// clockwise as seen in the image by the camera's rotation (Cycles' blade
/// rotation, for one: 0 = a vertex pointing right), squeezed keeping the area.
void unit_outline(const Aperture& a, std::vector<double>& xs, std::vector<double>& ys)
{
    const double theta = a.rotation_deg * pi / 180.0;
    const int n = a.shape == ApertureShape::Polygon ? a.blades : 0;
    auto add = [&](double phi, double rho) {
        xs.push_back(rho * std::cos(phi));
        ys.push_back(rho * std::sin(phi));  // image y points down: clockwise
    };
    if (a.shape == ApertureShape::Polygon && a.roundness == 0.0) {
        for (int i = 0; i < n; ++i)
            add(theta + 2.0 * pi * i / n, 1.0);
    } else {
        // The radial function of a regular n-gon, blended towards the
        // circle, sampled; the samples are scaled so that the circle's
        // polygon of samples has the circle's area (a disc, and roundness 1,
        // keep area π exactly).
        const int samples = 720;
        const double sampling = std::sqrt(pi / (0.5 * samples * std::sin(2.0 * pi / samples)));
        for (int i = 0; i < samples; ++i) {
            const double phi = 2.0 * pi * i / samples;
            double rho = 1.0;
            if (n > 0) {
                const double sector = 2.0 * pi / n;
                const double local = std::fmod(phi - theta + 8.0 * pi, sector) - 0.5 * sector;
                const double polygon = std::cos(0.5 * sector) / std::cos(local);
                rho = (1.0 - a.roundness) * polygon + a.roundness;
            }
            add(phi, rho * sampling);
        }
    }
    const double sx = std::sqrt(a.aspect), sy = 1.0 / sx;
    for (size_t i = 0; i < xs.size(); ++i) {
        xs[i] *= sx;
        ys[i] *= sy;
    }
}

/// The chord of a convex outline at height y: [left, right], or empty.
bool outline_chord(const std::vector<double>& xs, const std::vector<double>& ys, double y,
                   double& left, double& right)
{
    left = INFINITY;
    right = -INFINITY;
    for (size_t i = 0, j = xs.size() - 1; i < xs.size(); j = i++) {
        const double y0 = ys[j], y1 = ys[i];
        if ((y < std::min(y0, y1)) || (y > std::max(y0, y1)) || y0 == y1)
            continue;
        const double x = xs[j] + (y - y0) / (y1 - y0) * (xs[i] - xs[j]);
        left = std::min(left, x);
        right = std::max(right, x);
    }
    return right > left;
}

}  // namespace

ApertureProfile::ApertureProfile(const Aperture& aperture)
{
    std::vector<double> xs, ys;
    unit_outline(aperture, xs, ys);
    m_ymin = INFINITY;
    m_ymax = -INFINITY;
    m_extent = 0.0;
    for (size_t i = 0; i < xs.size(); ++i) {
        m_extent = std::max({ m_extent, std::abs(xs[i]), std::abs(ys[i]) });
        m_ymin = std::min(m_ymin, ys[i]);
        m_ymax = std::max(m_ymax, ys[i]);
    }
    // The unit chord, finely sampled in y and linear between samples, and
    // its area and first moment in x integrated from the bottom up, so
    // that a row's area and centre cost two table lookups.
    const int samples = 4096;
    m_ystep = (m_ymax - m_ymin) / (samples - 1);
    m_left.assign(samples, 0.0);
    m_right.assign(samples, 0.0);
    for (int i = 0; i < samples; ++i)
        if (!outline_chord(xs, ys, m_ymin + i * m_ystep, m_left[i], m_right[i]))
            m_left[i] = m_right[i] = 0.0;  // a vertex: an empty chord
    m_area.assign(samples, 0.0);
    m_moment.assign(samples, 0.0);
    for (int i = 1; i < samples; ++i) {
        m_area[i] = m_area[i - 1] + segment_area(i - 1, 1.0);
        m_moment[i] = m_moment[i - 1] + segment_moment(i - 1, 1.0);
    }
}

double ApertureProfile::segment_area(int i, double f) const
{
    // The chord is linear over the segment: the trapezoid rule is exact.
    const double l0 = m_right[i] - m_left[i];
    const double l1 = l0 + f * ((m_right[i + 1] - m_left[i + 1]) - l0);
    return 0.5 * f * m_ystep * (l0 + l1);
}

double ApertureProfile::segment_moment(int i, double f) const
{
    // The integrand (right² − left²)/2 is quadratic: Simpson's rule is exact.
    auto at = [&](double t) {
        const double l = m_left[i] + t * (m_left[i + 1] - m_left[i]);
        const double r = m_right[i] + t * (m_right[i + 1] - m_right[i]);
        return 0.5 * (r * r - l * l);
    };
    return f * m_ystep / 6.0 * (at(0.0) + 4.0 * at(0.5 * f) + at(f));
}

void ApertureProfile::integrals(double y, double& area, double& moment) const
{
    const double u = std::clamp((y - m_ymin) / m_ystep, 0.0, double(m_area.size() - 1));
    const size_t i = std::min(size_t(u), m_area.size() - 2);
    const double f = u - double(i);
    area = m_area[i] + segment_area(int(i), f);
    moment = m_moment[i] + segment_moment(int(i), f);
}

double ApertureProfile::rows(double r, std::vector<RowSpan>& spans) const
{
    // Each row [j - 1/2, j + 1/2] gets one interval whose length is the
    // outline's area in that row, centred on the area's centre, so a row's
    // energy is exact whatever its shape.
    r = std::max(min_radius, r);
    spans.clear();
    const int first = int(std::floor(m_ymin * r + 0.5));
    const int last = int(std::floor(m_ymax * r + 0.5));
    double area = 0.0;
    double below_area, below_moment;
    integrals((first - 0.5) / r, below_area, below_moment);
    for (int j = first; j <= last; ++j) {
        double above_area, above_moment;
        integrals((j + 0.5) / r, above_area, above_moment);
        const double length = (above_area - below_area) * r * r;
        const double moment = (above_moment - below_moment) * r * r * r;
        below_area = above_area;
        below_moment = above_moment;
        if (length <= 0.0)
            continue;
        const double mid = moment / length;
        spans.push_back({ j, mid - 0.5 * length, mid + 0.5 * length });
        area += length;
    }
    return area;
}

double BoxProfile::rows(double r, std::vector<RowSpan>& spans) const
{
    const BoxHalfWidths h = box_half_widths(r, m_aspect);
    spans.clear();
    double area = 0.0;
    for (int j = -int(std::ceil(h.y - 0.5)); j <= int(std::ceil(h.y - 0.5)); ++j) {
        const double height = std::min(j + 0.5, h.y) - std::max(j - 0.5, -h.y);
        spans.push_back({ j, -h.x, h.x, height });
        area += 2.0 * h.x * height;
    }
    return area;
}

double BoxProfile::extent() const
{
    return 0.5 * std::sqrt(pi) * std::max(std::sqrt(m_aspect), 1.0 / std::sqrt(m_aspect));
}

bool MaskProfile::set_shape(const OIIO::ImageBuf& image, double aspect, const Imath::V3d& luma,
                            std::string& error)
{
    const float wr = float(luma.x), wg = float(luma.y), wb = float(luma.z);
    const OIIO::ROI roi = image.roi();
    const int nc = image.nchannels();
    std::vector<float> luminance(roi.npixels());
    float peak = 0.0f;
    for (int y = 0; y < roi.height(); ++y)
        for (int x = 0; x < roi.width(); ++x) {
            float c[4] = { 0, 0, 0, 0 };
            image.getpixel(roi.xbegin + x, roi.ybegin + y, c, std::min(nc, 4));
            const float l = nc >= 3 ? wr * c[0] + wg * c[1] + wb * c[2] : c[0];
            luminance[size_t(y) * roi.width() + x] = l;
            if (std::isfinite(l))
                peak = std::max(peak, l);
        }
    if (!(peak > 0.0f)) {
        error = "the aperture mask is empty (all black)";
        return false;
    }
    double count = 0.0, sx = 0.0, sy = 0.0;
    m_runs.assign(roi.height(), {});
    for (int y = 0; y < roi.height(); ++y)
        for (int x = 0; x < roi.width(); ++x) {
            if (!(luminance[size_t(y) * roi.width() + x] >= 0.5f * peak))
                continue;
            std::vector<Run>& row = m_runs[y];
            if (!row.empty() && row.back().end == x)
                ++row.back().end;
            else
                row.push_back({ x, x + 1 });
            count += 1.0;
            sx += x + 0.5;
            sy += y + 0.5;
        }
    m_cx = sx / count;
    m_cy = sy / count;
    // count mask pixels become area π; the squeeze keeps the area.
    const double unit = std::sqrt(pi / count);
    m_sx = unit * std::sqrt(aspect);
    m_sy = unit / std::sqrt(aspect);
    measure_extent();
    return true;
}

void MaskProfile::measure_extent()
{
    double extent = 0.0;
    for (int y = 0; y < int(m_runs.size()); ++y)
        for (const Run& run : m_runs[y])
            extent = std::max({ extent, std::abs(run.begin - m_cx) * m_sx,
                                std::abs(run.end - m_cx) * m_sx, std::abs(y - m_cy) * m_sy,
                                std::abs(y + 1 - m_cy) * m_sy });
    m_extent = extent;
}

std::shared_ptr<const MaskProfile> MaskProfile::squeezed(double factor) const
{
    auto shape = std::make_shared<MaskProfile>(*this);
    shape->m_sx *= std::sqrt(factor);
    shape->m_sy /= std::sqrt(factor);
    shape->measure_extent();
    return shape;
}

double MaskProfile::rows(double r, std::vector<RowSpan>& spans) const
{
    r = std::max(min_radius, r);
    spans.clear();
    const int sub = 8;
    const int mask_rows = int(m_runs.size());
    const int reach = int(std::ceil(r * m_extent)) + 1;
    double area = 0.0;
    for (int j = -reach; j <= reach; ++j)
        for (int s = 0; s < sub; ++s) {
            // The sub-row's centre, in mask pixels.
            const double y = (j - 0.5 + (s + 0.5) / sub) / (r * m_sy) + m_cy;
            const int my = int(std::floor(y));
            if (my < 0 || my >= mask_rows)
                continue;
            for (const Run& run : m_runs[my]) {
                spans.push_back({ j, (run.begin - m_cx) * m_sx * r, (run.end - m_cx) * m_sx * r,
                                  1.0 / sub });
                area += (run.end - run.begin) * m_sx * r / sub;
            }
        }
    return area;
}

Psf aperture_psf(std::shared_ptr<const RowProfile> profile)
{
    return [profile](double r) {
        const ProgramFamily family(profile, 1, 1.0 / radius_bins_per_pixel, r);
        const ProgramBlend blend = family.pick(r);
        return family.program(blend.k).footprint(blend.t);
    };
}

}  // namespace defocus
