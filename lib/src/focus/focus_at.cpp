#include <defocus/focus/focus_at.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include <OpenImageIO/strutil.h>

namespace defocus {

using OIIO::Strutil::fmt::format;

namespace {

/// (depth, alpha) of every surface at a pixel, from all of the scene.
std::vector<std::pair<float, float>> surfaces_at(const Scene& scene, int x, int y)
{
    std::vector<std::pair<float, float>> found;
    for_each_content(scene,
        [&](const Layer& layer) {
            if (!layer.color.roi().contains(x, y))
                return true;
            const float a = static_cast<const float*>(layer.color.pixeladdr(x, y))[3];
            if (a > 0.0f)
                found.emplace_back(*static_cast<const float*>(layer.depth.pixeladdr(x, y)), a);
            return true;
        },
        [&](const DeepImage& deep) {
            if (!deep.roi.contains(x, y))
                return true;
            const int64_t i = deep.pixel_index(x, y);
            for (uint64_t s = deep.offsets[i]; s < deep.offsets[i + 1]; ++s)
                found.emplace_back(deep.samples[s].z, deep.samples[s].a);
            return true;
        });
    return found;
}

/// Where front-to-back coverage first reaches one half; +inf when never.
float opaque_depth(std::vector<std::pair<float, float>> surfaces)
{
    std::sort(surfaces.begin(), surfaces.end());
    float coverage = 0.0f;
    for (const auto& [z, a] : surfaces) {
        coverage += (1.0f - coverage) * std::min(a, 1.0f);
        if (coverage >= 0.5f)
            return z;
    }
    return INFINITY;
}

}  // namespace

bool focus_distance_at(const Scene& scene, double x, double y, double& distance,
                       std::string& error, int window)
{
    const OIIO::ImageSpec& s = scene.spec;
    if (!(x >= 0 && x < s.full_width && y >= 0 && y < s.full_height)) {
        error = format("--focus-at {},{} is outside the {}x{} display window", x, y,
                       s.full_width, s.full_height);
        return false;
    }
    const int cx = s.full_x + int(x), cy = s.full_y + int(y);
    std::vector<float> depths;
    for (int py = cy - window / 2; py <= cy + window / 2; ++py)
        for (int px = cx - window / 2; px <= cx + window / 2; ++px) {
            const float z = opaque_depth(surfaces_at(scene, px, py));
            if (std::isfinite(z))
                depths.push_back(z);
        }
    if (depths.empty()) {
        error = format("--focus-at {},{}: nothing opaque there to focus on", x, y);
        return false;
    }
    const size_t middle = depths.size() / 2;
    std::nth_element(depths.begin(), depths.begin() + middle, depths.end());
    distance = depths[middle];
    return true;
}

bool shot_camera(const Shot& shot, const Scene& scene, int frame, Camera& camera,
                 std::string& error)
{
    camera = camera_at(shot, frame);
    if (!shot.focus_at.empty()) {
        const Keyframes::Value at = shot.focus_at.at(frame, Interpolation::Linear);
        if (!focus_distance_at(scene, at[0], at[1], camera.focus_distance, error,
                               2 * shot.focus_at_radius + 1))
            return false;
        camera.focus_x = at[0];
        camera.focus_y = at[1];
    }
    return check_camera(camera, scene.spec.roi_full(), error);
}

}  // namespace defocus
