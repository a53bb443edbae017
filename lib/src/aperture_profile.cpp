#include <defocus/aperture_profile.h>

#include <algorithm>
#include <cmath>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/strutil.h>

namespace defocus {

namespace {

constexpr double pi = 3.14159265358979323846;
constexpr int steps_per_pixel = 16;  // radius steps of the row tables
constexpr double min_radius = 0.5;   // a disc inside its own pixel

/// The unit outline: counterclockwise as seen in the image (y down), area π.
void unit_outline(const Aperture& a, std::vector<double>& xs, std::vector<double>& ys)
{
    const double theta = a.rotation_deg * pi / 180.0;
    const int n = a.shape == ApertureShape::Polygon ? a.blades : 0;
    auto add = [&](double phi, double rho) {
        xs.push_back(rho * std::cos(phi));
        ys.push_back(-rho * std::sin(phi));  // image y points down
    };
    if (a.shape == ApertureShape::Polygon && a.roundness == 0.0) {
        for (int i = 0; i < n; ++i)
            add(theta + 2.0 * pi * i / n, 1.0);
    } else {
        // The radial function of a regular n-gon, blended towards the circle.
        const int samples = 720;
        for (int i = 0; i < samples; ++i) {
            const double phi = 2.0 * pi * i / samples;
            double rho = 1.0;
            if (n > 0) {
                const double sector = 2.0 * pi / n;
                const double local = std::fmod(phi - theta + 8.0 * pi, sector) - 0.5 * sector;
                const double polygon = std::cos(0.5 * sector) / std::cos(local);
                rho = (1.0 - a.roundness) * polygon + a.roundness;
            }
            add(phi, rho);
        }
    }
    // Anamorphic squeeze, keeping the area.
    const double sx = std::sqrt(a.aspect), sy = 1.0 / sx;
    double area = 0.0;
    for (size_t i = 0; i < xs.size(); ++i) {
        xs[i] *= sx;
        ys[i] *= sy;
    }
    for (size_t i = 0, j = xs.size() - 1; i < xs.size(); j = i++)
        area += xs[j] * ys[i] - xs[i] * ys[j];
    const double scale = std::sqrt(pi / (0.5 * std::abs(area)));
    for (size_t i = 0; i < xs.size(); ++i) {
        xs[i] *= scale;
        ys[i] *= scale;
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

ApertureProfile::ApertureProfile(const Aperture& aperture, double max_radius)
    : m_max_radius(std::max(min_radius, max_radius))
{
    std::vector<double> xs, ys;
    unit_outline(aperture, xs, ys);
    double extent = 0.0;
    m_ymin = INFINITY;
    double ymax = -INFINITY;
    for (size_t i = 0; i < xs.size(); ++i) {
        extent = std::max({ extent, std::abs(xs[i]), std::abs(ys[i]) });
        m_ymin = std::min(m_ymin, ys[i]);
        ymax = std::max(ymax, ys[i]);
    }
    // The unit chord, finely sampled in y, so that building a row costs a
    // table lookup rather than a pass over the outline.
    const int samples = 4096;
    m_ystep = (ymax - m_ymin) / (samples - 1);
    for (int i = 0; i < samples; ++i) {
        double left, right;
        if (!outline_chord(xs, ys, m_ymin + i * m_ystep, left, right))
            left = right = 0.0;  // a vertex: an empty chord
        m_left.push_back(left);
        m_right.push_back(right);
    }
    m_reach = int(std::ceil(m_max_radius * extent)) + 2;
    const int last = int(std::ceil(m_max_radius * steps_per_pixel)) + 1;
    for (int k = 0; k <= last; ++k)
        m_tables.push_back(build(std::max(min_radius, double(k) / steps_per_pixel)));
}

bool ApertureProfile::chord(double y, double& left, double& right) const
{
    const double u = (y - m_ymin) / m_ystep;
    if (!(u >= 0.0 && u <= double(m_left.size() - 1)))
        return false;
    const size_t i = std::min(size_t(u), m_left.size() - 2);
    const double f = u - i;
    left = (1.0 - f) * m_left[i] + f * m_left[i + 1];
    right = (1.0 - f) * m_right[i] + f * m_right[i + 1];
    return right > left;
}

ApertureProfile::Table ApertureProfile::build(double r) const
{
    // Each row [j - 1/2, j + 1/2] gets one interval whose length is the
    // outline's area in that row (16 sub-rows), centred on the area's
    // centre, so a row's energy is exact whatever its shape.
    const double ymin = m_ymin * r, ymax = (m_ymin + m_ystep * (m_left.size() - 1)) * r;
    Table t;
    t.first_row = int(std::floor(ymin + 0.5));
    const int last_row = int(std::floor(ymax + 0.5));
    const int sub = 16;
    for (int j = t.first_row; j <= last_row; ++j) {
        double length = 0.0, moment = 0.0;
        for (int s = 0; s < sub; ++s) {
            const double y = j - 0.5 + (s + 0.5) / sub;
            double left, right;
            if (!chord(y / r, left, right))
                continue;
            const double l = (right - left) * r / sub;
            length += l;
            moment += l * 0.5 * (left + right) * r;
        }
        t.length.push_back(length);
        t.centre.push_back(length > 0.0 ? moment / length : 0.0);
    }
    return t;
}

double ApertureProfile::rows(double r, std::vector<RowSpan>& spans) const
{
    spans.clear();
    const double x = std::clamp(r, min_radius, m_max_radius) * steps_per_pixel;
    const int k = std::min(int(x), int(m_tables.size()) - 2);
    const double t = x - k;
    const Table& a = m_tables[k];
    const Table& b = m_tables[k + 1];
    const int first = std::min(a.first_row, b.first_row);
    const int last = std::max(a.first_row + int(a.length.size()),
                              b.first_row + int(b.length.size()));
    double area = 0.0;
    for (int j = first; j < last; ++j) {
        auto at = [j](const Table& tab, const std::vector<double>& v) {
            const int i = j - tab.first_row;
            return i >= 0 && i < int(v.size()) ? v[i] : 0.0;
        };
        const double la = at(a, a.length), lb = at(b, b.length);
        const double length = (1.0 - t) * la + t * lb;
        if (length <= 0.0)
            continue;
        const double centre = ((1.0 - t) * la * at(a, a.centre) + t * lb * at(b, b.centre))
                              / length;
        spans.push_back({ j, centre - 0.5 * length, centre + 0.5 * length });
        area += length;
    }
    return area;
}

bool MaskProfile::load(const std::string& filename, double aspect, double max_radius,
                       std::string& error)
{
    OIIO::ImageBuf image(filename);
    if (!image.read(0, 0, true, OIIO::TypeFloat)) {
        error = OIIO::Strutil::fmt::format("{}: cannot read the aperture mask: {}", filename,
                                           OIIO::Strutil::replace(image.geterror(), "\n", " ", true));
        return false;
    }
    const OIIO::ROI roi = image.roi();
    const int nc = image.nchannels();
    std::vector<float> luma(roi.npixels());
    float peak = 0.0f;
    for (int y = 0; y < roi.height(); ++y)
        for (int x = 0; x < roi.width(); ++x) {
            float c[4] = { 0, 0, 0, 0 };
            image.getpixel(roi.xbegin + x, roi.ybegin + y, c, std::min(nc, 4));
            const float l = nc >= 3 ? 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2] : c[0];
            luma[size_t(y) * roi.width() + x] = l;
            if (std::isfinite(l))
                peak = std::max(peak, l);
        }
    if (!(peak > 0.0f)) {
        error = filename + ": the aperture mask is empty (all black)";
        return false;
    }
    double count = 0.0, sx = 0.0, sy = 0.0;
    m_runs.assign(roi.height(), {});
    for (int y = 0; y < roi.height(); ++y)
        for (int x = 0; x < roi.width(); ++x) {
            if (!(luma[size_t(y) * roi.width() + x] >= 0.5f * peak))
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
    m_max_radius = std::max(min_radius, max_radius);
    double extent = 0.0;
    for (int y = 0; y < roi.height(); ++y)
        for (const Run& run : m_runs[y])
            extent = std::max({ extent, std::abs(run.begin - m_cx) * m_sx,
                                std::abs(run.end - m_cx) * m_sx, std::abs(y - m_cy) * m_sy,
                                std::abs(y + 1 - m_cy) * m_sy });
    m_reach = int(std::ceil(m_max_radius * extent)) + 2;
    return true;
}

void MaskProfile::spans_at(double r, double weight, std::vector<RowSpan>& spans) const
{
    const int sub = 4;
    const int rows = int(m_runs.size());
    const int reach = int(std::ceil(r * (rows * m_sy))) + 1;
    for (int j = -reach; j <= reach; ++j)
        for (int s = 0; s < sub; ++s) {
            // The sub-row's centre, in mask pixels.
            const double y = (j - 0.5 + (s + 0.5) / sub) / (r * m_sy) + m_cy;
            const int my = int(std::floor(y));
            if (my < 0 || my >= rows)
                continue;
            for (const Run& run : m_runs[my])
                spans.push_back({ j, (run.begin - m_cx) * m_sx * r, (run.end - m_cx) * m_sx * r,
                                  weight / sub });
        }
}

double MaskProfile::rows(double r, std::vector<RowSpan>& spans) const
{
    spans.clear();
    const double x = std::clamp(r, min_radius, m_max_radius) * steps_per_pixel;
    const double k = std::floor(x), t = x - k;
    spans_at(k / steps_per_pixel, 1.0 - t, spans);
    if (t > 0.0)
        spans_at((k + 1) / steps_per_pixel, t, spans);
    double area = 0.0;
    for (const RowSpan& s : spans)
        area += s.weight * (s.right - s.left);
    return area;
}

Psf aperture_psf(std::shared_ptr<const RowProfile> profile)
{
    return [profile](double r) {
        std::vector<RowSpan> spans;
        const double area = profile->rows(r, spans);
        int x0 = 0, x1 = 0, y0 = 0, y1 = 0;
        for (const RowSpan& s : spans) {
            x0 = std::min(x0, int(std::floor(s.left + 0.5)));
            x1 = std::max(x1, int(std::floor(s.right + 0.5)));
            y0 = std::min(y0, s.row);
            y1 = std::max(y1, s.row);
        }
        Footprint fp;
        fp.x0 = x0;
        fp.y0 = y0;
        fp.width = x1 - x0 + 1;
        fp.height = y1 - y0 + 1;
        fp.weights.assign(size_t(fp.width) * fp.height, 0.0);
        for (const RowSpan& s : spans)
            for (int i = 0; i < fp.width; ++i) {
                // Pixel x0 + i covers [x0 + i - 1/2, x0 + i + 1/2].
                const double lo = std::max(s.left, x0 + i - 0.5);
                const double hi = std::min(s.right, x0 + i + 0.5);
                if (hi > lo)
                    fp.weights[size_t(s.row - fp.y0) * fp.width + i] += s.weight * (hi - lo) / area;
            }
        return fp;
    };
}

}  // namespace defocus
