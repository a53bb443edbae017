#include <defocus/io/planar_depth.h>

#include <atomic>
#include <climits>
#include <cmath>
#include <vector>

#include <OpenImageIO/strutil.h>

#include <defocus/focus/focus_at.h>
#include <defocus/shot/setting_words.h>

#include "util/parallel_rows.h"

namespace defocus {

using OIIO::Strutil::fmt::format;

namespace {

/// Per row of a window, the first value that meant nothing: its column
/// (none: INT_MIN) and the value; and how many there were.
struct Nonsense {
    explicit Nonsense(const OIIO::ROI& roi)
        : roi(roi)
        , first(size_t(roi.height()), { INT_MIN, 0.0f })
    {
    }

    /// Converts `z` at (x, y) in place; counts it when it means nothing.
    void convert(const PlanarDepth& planar, float& z, int x, int y, bool carries_light)
    {
        const double planar_z = planar(z, x, y);
        if (std::isnan(planar_z) && carries_light) {
            ++count;
            auto& row = first[size_t(y - roi.ybegin)];
            if (row.first == INT_MIN)
                row = { x, z };
        }
        z = float(planar_z);
    }

    /// The message for what was counted ("" when nothing).
    std::string message(DepthKind kind) const
    {
        if (count == 0)
            return "";
        for (size_t r = 0; r < first.size(); ++r)
            if (first[r].first != INT_MIN)
                return format("{} pixels or samples hold {} (the first at {},{}: {})",
                              count.load(),
                              kind == DepthKind::Inverse ? "negative or NaN inverse depth"
                                                         : "NaN depth",
                              first[r].first, roi.ybegin + int(r), first[r].second);
        return "";
    }

    OIIO::ROI roi;
    std::vector<std::pair<int, float>> first;
    std::atomic<int64_t> count { 0 };
};

void convert_layer(Layer& layer, const PlanarDepth& planar, Nonsense& nonsense, int nthreads)
{
    const OIIO::ROI roi = layer.depth.roi();
    OIIO::parallel_for(roi.ybegin, roi.yend, [&](int y) {
        float* z = static_cast<float*>(layer.depth.pixeladdr(roi.xbegin, y));
        const float* c = static_cast<const float*>(layer.color.pixeladdr(roi.xbegin, y));
        for (int x = 0; x < roi.width(); ++x)
            nonsense.convert(planar, z[x], roi.xbegin + x, y, c[4 * x + 3] > 0.0f);
    }, by_rows(nthreads));
}

void convert_deep(DeepImage& image, const PlanarDepth& planar, Nonsense& nonsense, int nthreads)
{
    const OIIO::ROI roi = image.roi;
    OIIO::parallel_for(roi.ybegin, roi.yend, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const int64_t p = image.pixel_index(x, y);
            for (uint64_t i = image.offsets[p]; i < image.offsets[p + 1]; ++i) {
                DeepSample& s = image.samples[i];
                nonsense.convert(planar, s.z, x, y, s.a > 0.0f);
                nonsense.convert(planar, s.zback, x, y, s.a > 0.0f);
            }
        }
    }, by_rows(nthreads));
}

}  // namespace

bool to_planar_depth(Scene& scene, const PlanarDepth& planar, std::string& error, int nthreads)
{
    if (planar.kind() == DepthKind::Z)
        return true;
    return for_each_content(scene,
        [&](Layer& layer) {
            Nonsense nonsense(layer.depth.roi());
            convert_layer(layer, planar, nonsense, nthreads);
            error = nonsense.message(planar.kind());
            return error.empty();
        },
        [&](DeepImage& image) {
            Nonsense nonsense(image.roi);
            convert_deep(image, planar, nonsense, nthreads);
            error = nonsense.message(planar.kind());
            return error.empty();
        });
}

DepthChoice frame_depth_kind(const Shot& shot, const OIIO::ImageSpec& header)
{
    DepthChoice choice;
    const std::string coc_channel = aov_name(Aov::Coc);
    if (is_given(shot, "depth-kind"))
        choice = { shot.depth_kind, setting_origin(shot, "depth-kind") };
    else if (header_depth_kind(header, choice.kind))
        choice.origin = std::string("file: ") + depth_kind_attribute;
    else if (shot.read.depth == coc_channel && header.channelindex(coc_channel) >= 0)
        choice = { DepthKind::Coc, format("{}: the coc AOV's channel", mention("depth", "coc")) };
    return choice;
}

bool planar_scene_depth(const Shot& shot, int frame, const DepthChoice& depth, Scene& scene,
                        std::string& error, int nthreads)
{
    if (depth.kind == DepthKind::Z)
        return true;
    Camera camera;
    CameraOrigins origins;
    lens_camera(shot, scene.spec, frame, camera, origins);
    const OIIO::ROI display = scene.spec.roi_full();
    // A CoC map's conflicts with focus settings are shot_camera's to refuse.
    if (depth.kind == DepthKind::Coc)
        camera = coc_map_camera(shot.camera, display);
    if (to_planar_depth(scene, PlanarDepth(depth.kind, camera, display, shot.read.depth_scale),
                        error, nthreads))
        return true;
    error = format("{} ({}): {}", mention("depth-kind", depth_kind_name(depth.kind)), depth.origin,
                   error);
    return false;
}

}  // namespace defocus
