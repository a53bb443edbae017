#include "layers/continued_lights.h"

#include <algorithm>
#include <cmath>

#include <OpenImageIO/parallel.h>

#include "layers/brightness.h"
#include "layers/observation.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// The widest light continued: larger bright patches are surfaces.
constexpr int widest_light = 64;

/// The fewest rim pixels a circle is fitted to.
constexpr size_t fewest_rim_pixels = 6;

/// The 4-neighbours' steps.
constexpr int steps[4][2] = { { 1, 0 }, { -1, 0 }, { 0, 1 }, { 0, -1 } };

using Pixel = ContinuedLights::Pixel;

/// Solves a·x = b for 3 unknowns by Cramer's rule; false where a is
/// singular.
bool solve3(const double a[3][3], const double b[3], double x[3])
{
    auto det = [](const double m[3][3]) {
        return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
               - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
               + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    };
    const double d = det(a);
    if (!(std::abs(d) > 1e-12))
        return false;
    for (int k = 0; k < 3; ++k) {
        double m[3][3];
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c)
                m[r][c] = c == k ? b[r] : a[r][c];
        x[k] = det(m) / d;
    }
    return true;
}

/// The circle through the centres of `points` that least squares
/// x² + y² + Dx + Ey + F (Kåsa 1976); false where they draw none.
bool kasa_circle(const std::vector<Pixel>& points, double& cx, double& cy, double& radius)
{
    // About the points' mean the centre c solves
    // [sxx sxy; sxy syy]·c = ½[sxz; syz], and r² = |c|² + mean(z).
    double mx = 0, my = 0;
    for (const Pixel& p : points) {
        mx += p.x + 0.5;
        my += p.y + 0.5;
    }
    mx /= double(points.size());
    my /= double(points.size());
    double sxx = 0, sxy = 0, syy = 0, sxz = 0, syz = 0, mean_z = 0;
    for (const Pixel& p : points) {
        const double x = p.x + 0.5 - mx, y = p.y + 0.5 - my, z = x * x + y * y;
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
        sxz += x * z;
        syz += y * z;
        mean_z += z;
    }
    mean_z /= double(points.size());
    const double det = sxx * syy - sxy * sxy;
    if (!(std::abs(det) > 1e-9))
        return false;
    const double ux = 0.5 * (sxz * syy - syz * sxy) / det, uy = 0.5 * (syz * sxx - sxz * sxy) / det;
    const double r2 = ux * ux + uy * uy + mean_z;
    if (!(r2 > 0.0))
        return false;
    cx = mx + ux;
    cy = my + uy;
    radius = std::sqrt(r2);
    return true;
}

/// How much of pixel (x, y) a disc covers, its edge taken as straight
/// across the pixel.
double disc_cover(double cx, double cy, double radius, int x, int y)
{
    return std::clamp(radius + 0.5 - std::hypot(x + 0.5 - cx, y + 0.5 - cy), 0.0, 1.0);
}

/// Refines the disc (cx, cy, radius) so that it covers each of `pixels` by
/// its `share` of the light: least squares by damped Gauss-Newton
/// (Levenberg-Marquardt).
bool fit_cover(const std::vector<Pixel>& pixels, const std::vector<double>& share, double& cx,
               double& cy, double& radius)
{
    auto cost = [&](double x0, double y0, double r) {
        double sum = 0.0;
        for (size_t i = 0; i < pixels.size(); ++i)
            sum += std::pow(disc_cover(x0, y0, r, pixels[i].x, pixels[i].y) - share[i], 2);
        return sum;
    };
    double current = cost(cx, cy, radius), damping = 1e-3;
    for (int iteration = 0; iteration < 50 && damping < 1e6; ++iteration) {
        double jtj[3][3] = {}, jtr[3] = {};
        for (size_t i = 0; i < pixels.size(); ++i) {
            const double dx = pixels[i].x + 0.5 - cx, dy = pixels[i].y + 0.5 - cy,
                         d = std::hypot(dx, dy), cover = radius + 0.5 - d;
            // Only the pixels the edge crosses move with the disc.
            if (!(cover > 0.0 && cover < 1.0 && d > 1e-9))
                continue;
            const double j[3] = { dx / d, dy / d, 1.0 }, r = cover - share[i];
            for (int a = 0; a < 3; ++a) {
                jtr[a] += j[a] * r;
                for (int b = 0; b < 3; ++b)
                    jtj[a][b] += j[a] * j[b];
            }
        }
        for (int a = 0; a < 3; ++a)
            jtj[a][a] *= 1.0 + damping;
        double step[3];
        if (!solve3(jtj, jtr, step))
            return false;
        const double tried = cost(cx - step[0], cy - step[1], radius - step[2]);
        if (!(tried < current)) {
            damping *= 10.0;
            continue;
        }
        cx -= step[0];
        cy -= step[1];
        radius -= step[2];
        current = tried;
        damping *= 0.3;
        if (std::abs(step[0]) + std::abs(step[1]) + std::abs(step[2]) < 1e-5)
            break;
    }
    return radius > 0.0;
}

}  // namespace

/// A light's seen pixels, 4-connected, and their bounds.
struct ContinuedLights::Patch {
    std::vector<Pixel> pixels;
    ROI box;
};

ContinuedLights::ContinuedLights(const FloatPixels& color, const FloatPixels& depth,
                                 const HoleMap& holes, const ROI& window, float highlight,
                                 int nthreads)
    : m_color(color)
    , m_depth(depth)
    , m_holes(holes)
    , m_window(window)
    , m_highlight(highlight)
{
    const int width = window.width(), height = window.height();
    if (width <= 0 || height <= 0)
        return;
    // Where a light may start: bright pixels beside a hole, found row by
    // row side by side; most layers have none.
    std::vector<std::vector<Pixel>> rows(static_cast<size_t>(height));
    parallel_for(window.ybegin, window.yend, [&](int y) {
        for (int x = window.xbegin; x < window.xend; ++x)
            if (bright(x, y) && beside_hole(x, y))
                rows[size_t(y - window.ybegin)].push_back({ x, y });
    }, by_rows(nthreads));
    std::vector<uint8_t> visited;
    auto mark = [&](int x, int y) -> uint8_t& {
        return visited[size_t(y - window.ybegin) * width + (x - window.xbegin)];
    };
    Patch patch;
    std::vector<Pixel> stack;
    for (const std::vector<Pixel>& seeds : rows)
        for (const Pixel& seed : seeds) {
            if (visited.empty())
                visited.assign(size_t(width) * height, 0);
            if (mark(seed.x, seed.y))
                continue;
            // The light's patch, 4-connected; a patch that outgrows a
            // light is a surface, and is not followed further.
            patch.pixels.clear();
            patch.box = ROI(seed.x, seed.x + 1, seed.y, seed.y + 1);
            stack.assign(1, seed);
            mark(seed.x, seed.y) = 1;
            while (!stack.empty() && patch.box.width() <= widest_light
                   && patch.box.height() <= widest_light) {
                const Pixel p = stack.back();
                stack.pop_back();
                patch.pixels.push_back(p);
                patch.box = roi_union(patch.box, ROI(p.x, p.x + 1, p.y, p.y + 1));
                for (const auto& s : steps)
                    if (bright(p.x + s[0], p.y + s[1]) && !mark(p.x + s[0], p.y + s[1])) {
                        mark(p.x + s[0], p.y + s[1]) = 1;
                        stack.push_back({ p.x + s[0], p.y + s[1] });
                    }
            }
            Light light;
            if (stack.empty() && patch.box.width() <= widest_light
                && patch.box.height() <= widest_light && fit(patch, light))
                m_lights.push_back(light);
        }
    m_bands.resize(size_t((height + band_rows - 1) / band_rows));
    for (size_t i = 0; i < m_lights.size(); ++i) {
        const Light& l = m_lights[i];
        const int first = std::max(0, int(std::floor(l.cy - l.reach)) - window.ybegin);
        const int last = std::min(height - 1, int(std::ceil(l.cy + l.reach)) - window.ybegin);
        for (int band = first / band_rows; band <= last / band_rows && first <= last; ++band)
            m_bands[size_t(band)].push_back(i);
    }
}

bool ContinuedLights::hidden(int x, int y) const
{
    return m_window.contains(x, y) && m_holes(x, y);
}

bool ContinuedLights::beside_hole(int x, int y) const
{
    // A surface continued behind the edge may lie between.
    for (const auto& s : steps)
        if (hidden(x + s[0], y + s[1]) || hidden(x + 2 * s[0], y + 2 * s[1]))
            return true;
    return false;
}

bool ContinuedLights::bright(int x, int y) const
{
    if (!m_window.contains(x, y) || *m_holes.row(x, y) != HiddenPixels::seen)
        return false;
    const float* c = m_color(x, y);
    return c[3] > 0.0f && brightness(c) > m_highlight;
}

bool ContinuedLights::fit(const Patch& patch, Light& light) const
{
    // The light inside its rim, and its rim away from the hole: where the
    // light ends on its own.
    std::vector<Pixel> rim;
    double inside[5] = { 0, 0, 0, 0, 0 };
    int inside_count = 0;
    for (const Pixel& p : patch.pixels) {
        bool edge = false;
        for (const auto& s : steps)
            edge = edge || !bright(p.x + s[0], p.y + s[1]);
        if (edge) {
            if (!beside_hole(p.x, p.y))
                rim.push_back(p);
            continue;
        }
        float value[5];
        observe(m_color, m_depth, p.x, p.y, value);
        for (int i = 0; i < 5; ++i)
            inside[i] += value[i];
        ++inside_count;
    }
    double cx, cy, radius;
    if (rim.size() < fewest_rim_pixels || inside_count == 0 || !kasa_circle(rim, cx, cy, radius))
        return false;
    // What each seen pixel around the light, away from the hole, holds of
    // it; and the surroundings' mean. A light's faint fringe (little of
    // the pixel covered, as bright as the light for what it covers) is the
    // light, not its surroundings.
    for (double& v : inside)
        v /= inside_count;
    std::vector<Pixel> around;
    std::vector<double> values, share;
    double surroundings[5] = { 0, 0, 0, 0, 0 }, floor = 0.0;
    int surrounding_count = 0;
    for (int y = patch.box.ybegin - 2; y < patch.box.yend + 2; ++y)
        for (int x = patch.box.xbegin - 2; x < patch.box.xend + 2; ++x) {
            if (!m_window.contains(x, y) || hidden(x, y) || beside_hole(x, y))
                continue;
            const float* c = m_color(x, y);
            around.push_back({ x, y });
            values.push_back(brightness(c));
            if (bright(x, y) || (c[3] > 0.0f && brightness(c) > m_highlight * c[3]))
                continue;
            float value[5];
            observe(m_color, m_depth, x, y, value);
            for (int i = 0; i < 5; ++i)
                surroundings[i] += value[i];
            floor += values.back();
            ++surrounding_count;
        }
    if (surrounding_count > 0) {
        for (double& v : surroundings)
            v /= surrounding_count;
        floor /= surrounding_count;
    }
    const double level = (inside[0] + inside[1] + inside[2]) / 3.0;
    if (!(level > floor))
        return false;
    for (double v : values)
        share.push_back((v - floor) / (level - floor));
    if (!fit_cover(around, share, cx, cy, radius) || radius > 0.5 * widest_light)
        return false;
    // The circle must hold the light it was drawn from.
    size_t outside = 0;
    for (const Pixel& p : patch.pixels)
        outside += std::hypot(p.x + 0.5 - cx, p.y + 0.5 - cy) > radius + 1.5;
    if (outside * 10 > patch.pixels.size())
        return false;
    light.cx = cx;
    light.cy = cy;
    light.radius = radius;
    light.reach = radius + std::max(2.0, radius);
    for (int i = 0; i < 5; ++i) {
        light.light[i] = float(inside[i]);
        light.around[i] = float(surroundings[i]);
    }
    return true;
}

bool ContinuedLights::at(int x, int y, float value[5]) const
{
    if (m_lights.empty() || !m_window.contains(x, y))
        return false;
    for (size_t i : m_bands[size_t((y - m_window.ybegin) / band_rows)]) {
        const Light& l = m_lights[i];
        if (std::hypot(x + 0.5 - l.cx, y + 0.5 - l.cy) >= l.reach)
            continue;
        const double cover = disc_cover(l.cx, l.cy, l.radius, x, y);
        for (int c = 0; c < 5; ++c)
            value[c] = float(cover * l.light[c] + (1.0 - cover) * l.around[c]);
        return true;
    }
    return false;
}

}  // namespace defocus
