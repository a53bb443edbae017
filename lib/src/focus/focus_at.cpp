#include <defocus/focus/focus_at.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include <OpenImageIO/strutil.h>

#include <defocus/shot/setting_words.h>

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
                       std::string& error, int window, double pixel_aspect)
{
    const OIIO::ImageSpec& s = scene.spec;
    if (!(x >= 0 && x < s.full_width && y >= 0 && y < s.full_height)) {
        error = format("{} is outside the {}x{} display window",
                       mention("focus-at", format("{},{}", x, y)), s.full_width, s.full_height);
        return false;
    }
    const int cx = s.full_x + int(x), cy = s.full_y + int(y);
    std::vector<float> depths;
    const int half_across = int(std::lround(window / 2 / pixel_aspect));
    for (int py = cy - window / 2; py <= cy + window / 2; ++py)
        for (int px = cx - half_across; px <= cx + half_across; ++px) {
            const float z = opaque_depth(surfaces_at(scene, px, py));
            if (std::isfinite(z))
                depths.push_back(z);
        }
    if (depths.empty()) {
        error = format("{}: nothing opaque there to focus on",
                       mention("focus-at", format("{},{}", x, y)));
        return false;
    }
    const size_t middle = depths.size() / 2;
    std::nth_element(depths.begin(), depths.begin() + middle, depths.end());
    distance = depths[middle];
    return true;
}

bool lens_camera(const Shot& shot, const OIIO::ImageSpec& header, int frame, Camera& camera,
                 CameraOrigins& origins)
{
    camera = camera_at(shot, frame);
    origins = { setting_origin(shot, "focal"), setting_origin(shot, "fstop"),
                setting_origin(shot, "focus"), setting_origin(shot, "sensor") };
    camera.pixel_aspect = header_pixel_aspect(header);
    bool has_focus = !shot.focus.empty();
    if (shot.camera_from_file) {
        // A sequence's frames are read one by one: each takes its own
        // header's values, so a focus pull baked into the render is followed.
        const HeaderCamera found = camera_from_header(header);
        auto take = [&](const HeaderValue& value, const char* setting, double& to,
                        std::string& origin) {
            if (!value.found() || is_given(shot, setting))
                return false;
            to = value.value;
            origin = "file: " + value.attribute;
            return true;
        };
        take(found.focal_length_mm, "focal", camera.focal_length_mm, origins.focal_length);
        take(found.fstop, "fstop", camera.fstop, origins.fstop);
        // The projection gives f/s; with a focal length known, the filmback.
        const bool focal_known = is_given(shot, "focal") || found.focal_length_mm.found();
        if (!is_given(shot, "sensor")
            && !take(found.sensor_width_mm, "sensor", camera.sensor_width_mm,
                     origins.sensor_width)
            && found.focal_over_filmback.found() && focal_known) {
            camera.sensor_width_mm = camera.focal_length_mm / found.focal_over_filmback.value;
            origins.sensor_width = "file: worldToNDC and the focal length";
        }
        if (shot.focus_at.empty())
            has_focus |= take(found.focus_distance, "focus", camera.focus_distance,
                              origins.focus);
    }
    return has_focus;
}

bool shot_camera(const Shot& shot, const Scene& scene, int frame, Camera& camera,
                 CameraOrigins& origins, std::string& error, DepthKind depth_kind)
{
    const OIIO::ROI display = scene.spec.roi_full();
    if (depth_kind == DepthKind::Coc) {
        if (error = coc_map_conflict(shot); !error.empty())
            return false;
        lens_camera(shot, scene.spec, frame, camera, origins);
        const Camera lens = camera;
        camera = coc_map_camera(shot.camera, display);
        camera.axis_pixel = lens.axis_pixel;
        camera.pixel_aspect = lens.pixel_aspect;
        origins = { "none", "none", "the CoC map", "none" };
        return check_camera(camera, display, error);
    }
    bool has_focus = lens_camera(shot, scene.spec, frame, camera, origins);
    if (!shot.focus_at.empty()) {
        const Keyframes::Value at = shot.focus_at.at(frame, Interpolation::Linear);
        if (!focus_distance_at(scene, at[0], at[1], camera.focus_distance, error,
                               2 * shot.focus_at_radius + 1, camera.pixel_aspect))
            return false;
        camera.focus_pixel = Imath::V2d(at[0], at[1]);
        origins.focus = setting_origin(shot, "focus-at");
        has_focus = true;
    }
    if (!has_focus) {
        error = format("no focus distance: give {} or {} (the file's header records none)",
                       mention("focus", "DIST"), mention("focus-at", "X,Y"));
        return false;
    }
    return check_camera(camera, display, error);
}

}  // namespace defocus
