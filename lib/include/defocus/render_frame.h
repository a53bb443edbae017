// One frame of a shot, from its files to the image to write:
//
//   read -> planar depth -> sanitize -> to scene-linear (bloom) -> focus ->
//   layers -> spread each layer -> composite -> from scene-linear -> metadata
//
// The defocus command and the OpenImageIO plugin both render through here.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <defocus/color/color_plan.h>
#include <defocus/composite/defocus_layers.h>
#include <defocus/io/planar_depth.h>
#include <defocus/io/shot_assets.h>
#include <defocus/layers/layered_scene.h>
#include <defocus/scene.h>
#include <defocus/io/camera_metadata.h>
#include <defocus/shot/shot.h>

namespace defocus {

struct FrameResult {
    std::string source;  ///< the files read, for messages
    Camera camera;       ///< as used; the focus measured when focusing at a pixel
    CameraOrigins camera_origins;  ///< where each camera value came from
    DepthChoice depth;             ///< what the input's depth held
    ColorPlan color;
    /// The result in the output colour space, with the input's metadata
    /// and the settings used (defocus:*, oiio:ColorSpace, compression).
    OIIO::ImageBuf image;
    OIIO::TypeDesc pixel_type;  ///< to write it as; once written, the type the file took
    /// The last channels of `image` that are data (composite/data_channels.h),
    /// written as float whatever pixel_type is.
    int data_channels = 0;
    PixelCounts fixed;
    std::vector<std::string> notes;  ///< how reading took what the files did not say
    std::string bloom;    ///< what bloom lifted ("" = off)
    std::string slicing;  ///< how flat or deep input was cut into layers ("" = not)
    std::string rebuilt;  ///< what of the layers' hidden backgrounds was rebuilt, and how ("" = none)
    std::string edges;    ///< how the layers were extended past the data window ("" = not)
    std::string holdout;  ///< the holdout that cut the result ("" = none)
    std::string data;     ///< the data channels carried, and as what ("" = none)
    std::vector<LayerReport> layers;
    /// How much of the frame was composited per part of the aperture.
    SubApertureReport cells;
    /// Seconds per stage: read, colour, slice, spread, composite (or focus
    /// map), colour out.
    std::vector<std::pair<std::string, double>> timings;
    /// In a run of frames side by side, how its stages overlapped other
    /// frames' (StageTimeline::finish); empty when none ran beside it.
    std::string overlap;
};

/// Called as each stage of a frame starts ("read", "colour", "slice",
/// "render", "data channels"), for progress display; false cancels the
/// frame there, which then fails with the error "cancelled". Long stages
/// also call it with nullptr, no new stage, only to ask whether to go on,
/// or with their name and how far they are ("data channels 12/134"; see
/// stage_of).
using StageCallback = std::function<bool(const char* stage)>;

/// The first half of a frame, shared by render_frame() and layerize: read
/// -> sanitize -> to scene-linear -> focus -> layers. Fills `layers` and,
/// of `result`, the source, camera, colour plan, pixel fixes, notes,
/// slicing and those stages' timings. False with `error` a one-line
/// message naming the file and the problem.
bool prepare_layers(const Shot& shot, int frame, const ShotAssets& assets, LayeredScene& layers,
                    FrameResult& result, std::string& error, const StageCallback& on_stage = {},
                    int nthreads = 0);

/// prepare_layers() of a scene already in memory (layers, flat renders or
/// deep images, as read_scene() gives them) in place of the shot's inputs;
/// its `source` names it in errors.
bool prepare_layers(Scene&& scene, const Shot& shot, int frame, const ShotAssets& assets,
                    LayeredScene& layers, FrameResult& result, std::string& error,
                    const StageCallback& on_stage = {}, int nthreads = 0);

/// Whether spreading `frame` of a shot fits its memory limit, as
/// render_frame() checks it from the inputs' headers before reading pixels;
/// false with `error` naming the files and the memory needed.
bool frame_fits(const Shot& shot, int frame, std::string& error);

/// The spec of `frame` of a shot as render_frame() gives it, from the
/// inputs' headers alone, without reading pixels or rendering: display and
/// data windows, channels R,G,B,A, the pixel type to write, metadata. With
/// OutputWindow::Grown the data window is the largest the blur can make;
/// when the shot focuses at a pixel the focus distance is not known yet and
/// defocus:focusDistance is left out.
bool frame_spec(const Shot& shot, int frame, const ShotAssets& assets, OIIO::ImageSpec& spec,
                std::string& error);

/// The camera `frame` of a shot renders with, and where each value came
/// from, as render_frame() finds it: the shot's settings, then the inputs'
/// headers (camera_from_file). Reads pixels only when the shot focuses at
/// a pixel, to measure the depth there. False with `error` a one-line
/// message naming the file and the problem.
bool frame_camera(const Shot& shot, int frame, Camera& camera, CameraOrigins& origins,
                  std::string& error);

/// Renders `frame` of a shot (the inputs' frame patterns and the keyframes
/// are taken at it) with its assets, read once for all frames
/// (read_shot_assets). False with `error` a one-line message naming the
/// file and the problem.
bool render_frame(const Shot& shot, int frame, const ShotAssets& assets,
                  FrameResult& result, std::string& error, const StageCallback& on_stage = {},
                  int nthreads = 0);

/// render_frame() of a scene already in memory in place of the shot's
/// inputs (see prepare_layers).
bool render_scene(Scene&& scene, const Shot& shot, int frame, const ShotAssets& assets,
                  FrameResult& result, std::string& error, const StageCallback& on_stage = {},
                  int nthreads = 0);

}  // namespace defocus
