#include <defocus/render_frame.h>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>
#include <OpenImageIO/timer.h>

#include <defocus/color/bloom.h>
#include <defocus/composite/coc_aov.h>
#include <defocus/composite/confidence.h>
#include <defocus/composite/data_channels.h>
#include <defocus/composite/deep_result.h>
#include <defocus/composite/holdout.h>
#include <defocus/focus/focus_at.h>
#include <defocus/focus/focus_map.h>
#include <defocus/io/frames.h>
#include <defocus/io/image_output.h>
#include <defocus/io/planar_depth.h>
#include <defocus/io/scene_io.h>
#include <defocus/layers/edges.h>
#include <defocus/layers/layer_view.h>
#include <defocus/layers/layering.h>
#include <defocus/shot/setting_words.h>

#include "composite/spread_memory.h"
#include "io/output_metadata.h"

namespace defocus {

using namespace OIIO;
using Strutil::fmt::format;

namespace {

/// The pixel type to write: the shot's, else that of the input's colour.
TypeDesc output_pixel_type(const Shot& shot, const ImageSpec& input)
{
    if (shot.pixel_type != TypeUnknown)
        return shot.pixel_type;
    const int r = input.channelindex("R");
    return r >= 0 ? input.channelformat(r) : input.format;
}

/// The type of a deep result's colour and alpha: half or float, as
/// output_pixel_type() says.
TypeDesc deep_color_type(const Shot& shot, const ImageSpec& input)
{
    return output_pixel_type(shot, input) == TypeHalf ? TypeHalf : TypeFloat;
}

/// Whether stage `name` may start; false with `error` where the callback
/// cancels the frame.
bool run_stage(const StageCallback& on_stage, const char* name, std::string& error)
{
    if (!on_stage || on_stage(name))
        return true;
    error = "cancelled";
    return false;
}

/// A note, for -v, of the data channels the input has and a shot that
/// names none leaves out: a user may not know they could be carried.
void note_data_channels(const ImageSpec& input, std::vector<std::string>& notes)
{
    DataPlan found;
    std::string unused;
    if (!plan_data_channels(input, "auto", found, unused))
        return;
    std::vector<std::string> sets;
    auto add = [&](const std::string& name) {
        if (std::find(sets.begin(), sets.end(), name) == sets.end())
            sets.push_back(name);
    };
    for (const DataChannel& c : found.channels)
        add(c.name.substr(0, c.name.rfind('.')));
    for (const CryptoSet& set : found.crypto)
        add(set.name);
    if (!sets.empty())
        notes.push_back(format("data channels left out: {} ({} carries them)",
                               Strutil::join(sets, ", "), mention("data-channels", "auto")));
}

/// prepare_layers() from the scene read; `timer` started with the read.
bool layer_scene(Scene&& scene, const Shot& shot, int frame, const ShotAssets& assets,
                 LayeredScene& layered, FrameResult& out, std::string& error,
                 const StageCallback& on_stage, int nthreads, Timer& timer)
{
    auto lap = [&](const char* name) { out.timings.emplace_back(name, timer.lap()); };
    out.source = scene.source;
    out.notes  = scene.notes;
    if (shot.data_channels == Shot().data_channels)
        note_data_channels(scene.spec, out.notes);
    // The readers name the file that failed; later stages' errors are
    // named here, once.
    auto fail = [&]() {
        error = out.source + ": " + error;
        return false;
    };
    out.depth = frame_depth_kind(shot, scene.spec);
    if (!planar_scene_depth(shot, frame, out.depth, scene, error, nthreads))
        return fail();
    out.fixed = sanitize(scene, nthreads);
    lap("read");

    if (!run_stage(on_stage, "colour", error))
        return false;
    ColorPlan& color = out.color;
    if (!plan_color(color, assets.color, assets.no_color, shot.input_space, shot.output_space,
                    scene.spec, error)
        || (color.convert_input
            && !convert_scene(scene, *color.config, color.input, color.working, error,
                              nthreads)))
        return fail();
    if (!shot.bloom.empty()) {
        const Keyframes::Value at = shot.bloom.at(frame, Interpolation::Linear);
        const int64_t lifted = apply_bloom(scene, { at[0], at[1] }, nthreads);
        out.bloom = format("bloom: {} pixels or samples lifted, those above {:g} by {:g}x",
                           lifted, at[0], at[1]);
    }
    lap("colour");

    if (!run_stage(on_stage, "slice", error))
        return false;
    if (!shot_camera(shot, scene, frame, out.camera, out.camera_origins, error, out.depth.kind))
        return fail();
    const CircleOfConfusion coc(out.camera, scene.spec.roi_full());
    const bool to_slice = !scene.flat.empty() || !scene.deep.empty();
    const size_t layers_given = scene.layers.size();
    Slicing slicing;
    if (!decompose_layers(std::move(scene), coc, shot.layering, layered, slicing, error,
                          nthreads, [&] { return !on_stage || on_stage(nullptr); }))
        return fail();
    const LayerBounds& bounds = slicing.bounds;
    layered.luma = luma_weights(color.config.get());
    if (to_slice) {
        std::vector<std::string> edges;
        for (int k = 0; k <= bounds.count(); ++k)
            edges.push_back(format("{:.3g}", bounds.boundary(k)));
        // Slices nothing falls into make no layer.
        const int made = int(layered.layers.size() - layers_given);
        const int empty = bounds.count() - made;
        out.slicing = format("sliced into {} depth layer(s){}, bounds in px of CoC: {}; {} "
                             "mixed pixel(s) on silhouettes split in two",
                             made,
                             empty > 0 ? format(" ({} empty slice(s) dropped)", empty) : "",
                             Strutil::join(edges, " "), slicing.mixed_pixels);
        const RebuiltPixels& rebuilt = slicing.rebuilt;
        if (rebuilt.total() > 0)
            out.rebuilt = format("hidden background rebuilt: {} px ({} patterns copied across "
                                 "holes, {} along lines, {} smooth fill, {} continued "
                                 "behind edges)",
                                 rebuilt.total(), rebuilt.patterns, rebuilt.lines,
                                 rebuilt.smooth, rebuilt.continued);
    }
    lap("slice");
    return true;
}

}  // namespace

// What spreading holds at the least (see spread_bytes): the parts as read,
// which the layers hold again grown by their blur, and the image the frame
// is spread into with its accumulator over the inputs' data window. Checked
// from the headers, so that a scene too large to spread is not read and
// sliced first (a 41 megapixel strip took seconds to be refused after
// slicing); only the blur, which the depths give, is left to the check
// after reading.
bool frame_fits(const Shot& shot, int frame, std::string& error)
{
    if (shot.output != OutputKind::Image)
        return true;
    const std::vector<std::string> inputs = frame_inputs(shot, frame);
    ImageSpec input;
    if (!read_scene_spec(inputs, frame_read_options(shot, frame), input, error))
        return false;
    const double bytes = declared_bytes(inputs, shot.read.memory_limit)
                         + result_bytes(double(input.image_pixels()));
    if (shot.read.memory_limit.allows(bytes))
        return true;
    error = format("{}: {}", Strutil::join(inputs, " "),
                   shot.read.memory_limit.exceeded(
                       format("spreading a data window of {}x{}", input.width, input.height),
                       bytes));
    return false;
}

namespace {

/// The data channels `shot` carries from the scene whose header is `input`;
/// false with `error` naming the files.
bool frame_data_plan(const Shot& shot, int frame, const ImageSpec& input, DataPlan& plan,
                     std::string& error)
{
    const std::string files = Strutil::join(frame_inputs(shot, frame), " ");
    if (!plan_data_channels(input, shot.data_channels, plan, error)) {
        error = format("{}: {}", files, error);
        return false;
    }
    if (!plan.distinct_names(output_aov(shot), error)) {
        error = format("{}: {}: {}", files, mention("data-channels", shot.data_channels), error);
        return false;
    }
    return true;
}

/// How a frame's files are read, with the data channels its shot carries.
bool frame_reading(const Shot& shot, int frame, ReadOptions& options, std::string& error)
{
    options = frame_read_options(shot, frame);
    if (shot.data_channels == Shot().data_channels)
        return true;
    ImageSpec input;
    DataPlan plan;
    if (!read_scene_spec(frame_inputs(shot, frame), options, input, error)
        || !frame_data_plan(shot, frame, input, plan, error))
        return false;
    options.data_channels = plan.input_channels();
    return true;
}

}  // namespace

bool prepare_layers(const Shot& shot, int frame, const ShotAssets& assets, LayeredScene& layered,
                    FrameResult& out, std::string& error, const StageCallback& on_stage,
                    int nthreads)
{
    Timer timer;
    Scene scene;
    ReadOptions options;
    // A focus the shot does not give must come from the headers: where
    // they have none, that is said before the pixels are read.
    Camera camera;
    CameraOrigins origins;
    if (!run_stage(on_stage, "read", error)
        || (shot.focus.empty() && shot.focus_at.empty()
            && !frame_camera(shot, frame, camera, origins, error))
        || !frame_fits(shot, frame, error) || !frame_reading(shot, frame, options, error)
        || !read_scene(frame_inputs(shot, frame), options, scene, error))
        return false;
    return layer_scene(std::move(scene), shot, frame, assets, layered, out, error, on_stage,
                       nthreads, timer);
}

bool frame_camera(const Shot& shot, int frame, Camera& camera, CameraOrigins& origins,
                  std::string& error)
{
    const std::vector<std::string> inputs = frame_inputs(shot, frame);
    const ReadOptions options = frame_read_options(shot, frame);
    Scene scene;
    if (shot.focus_at.empty() ? !read_scene_spec(inputs, options, scene.spec, error)
                              : !read_scene(inputs, options, scene, error))
        return false;
    const DepthChoice depth = frame_depth_kind(shot, scene.spec);
    if (!shot.focus_at.empty() && !planar_scene_depth(shot, frame, depth, scene, error)) {
        error = Strutil::join(inputs, " ") + ": " + error;
        return false;
    }
    sanitize(scene);
    if (shot_camera(shot, scene, frame, camera, origins, error, depth.kind))
        return true;
    error = Strutil::join(inputs, " ") + ": " + error;
    return false;
}

bool prepare_layers(Scene&& scene, const Shot& shot, int frame, const ShotAssets& assets,
                    LayeredScene& layered, FrameResult& out, std::string& error,
                    const StageCallback& on_stage, int nthreads)
{
    Timer timer;
    if (!run_stage(on_stage, "read", error))
        return false;
    return layer_scene(std::move(scene), shot, frame, assets, layered, out, error, on_stage,
                       nthreads, timer);
}

namespace {

/// The shot's holdout at `frame`, front to back (none when the shot names
/// none), over the scene's display window.
bool read_holdout(const Shot& shot, int frame, const ImageSpec& scene,
                  std::shared_ptr<const DeepImage>& holdout, std::string& error)
{
    holdout.reset();
    if (shot.holdout.empty())
        return true;
    ReadOptions options;
    options.depth_scale  = shot.read.depth_scale;
    options.memory_limit = shot.read.memory_limit;
    // --depth is the input's: a holdout carries its own depths.
    options.missing_depth_remedy = format(
        "{} takes a deep EXR or a flat render with a Z channel, whose depths say what the "
        "holdout hides", mention("holdout"));
    Scene read;
    if (!read_scene({ frame_path(shot.holdout, source_frame(shot, frame)) }, options, read,
                    error))
        return false;
    const ImageSpec& h = read.spec;
    if (h.full_x != scene.full_x || h.full_y != scene.full_y || h.full_width != scene.full_width
        || h.full_height != scene.full_height) {
        error = format("{}: the holdout's display window {}x{} is not the input's {}x{}",
                       read.source, h.full_width, h.full_height, scene.full_width,
                       scene.full_height);
        return false;
    }
    // --depth-kind is the input's: a holdout's own header may say its kind.
    // Its depths are compared with the scene's, so a CoC map cannot be one.
    DepthChoice depth;
    if (header_depth_kind(h, depth.kind)) {
        depth.origin = std::string("file: ") + depth_kind_attribute;
        if (depth.kind == DepthKind::Coc) {
            error = format("{}: a holdout's depth must be a distance, and its header says it "
                           "is a CoC map ({} coc)",
                           read.source, depth_kind_attribute);
            return false;
        }
        if (!planar_scene_depth(shot, frame, depth, read, error)) {
            error = read.source + ": " + error;
            return false;
        }
    }
    sanitize(read);
    holdout = std::make_shared<const DeepImage>(holdout_image(read));
    return true;
}

/// What -v says of the holdout ("" for none).
std::string holdout_line(const Shot& shot, int frame, const DeepImage* holdout)
{
    return holdout ? format("holdout: {} ({} samples in {} pixels)",
                            frame_path(shot.holdout, source_frame(shot, frame)),
                            holdout->samples.size(), holdout->roi.npixels())
                   : "";
}

/// The confidence AOV of `image`, defocused from `layered` as the shot
/// says: the scene's rebuilt part, and that part by method, each spread and
/// composited the same way.
bool confidence_aov(ImageBuf& confidence, const ImageBuf& image, const LayeredScene& layered,
                    const Shot& shot, const Camera& camera, const ApertureImages& images,
                    std::string& error, int nthreads)
{
    ImageBuf light(image.spec()), by_method(image.spec());  // none, unless something was rebuilt
    using PartOf = bool (*)(const LayeredScene&, LayeredScene&, int);
    const std::pair<PartOf, ImageBuf*> parts[]
        = { { rebuilt_part, &light }, { rebuilt_by_method, &by_method } };
    for (const auto& [part_of, spread] : parts) {
        LayeredScene part;
        if (part_of(layered, part, nthreads)
            && !defocus_layers(*spread, part, camera, shot.spread, images, shot.window, nullptr,
                               nullptr, nthreads)) {
            error = spread->geterror();
            return false;
        }
    }
    if (!light_fraction(confidence, image, light, by_method, layered.luma, nthreads)) {
        error = confidence.geterror();
        return false;
    }
    return true;
}

/// The shot's extra channel for `image`, defocused from `layered`: left
/// uninitialised when it asks for none.
bool aov_channel(ImageBuf& aov, const ImageBuf& image, const LayeredScene& layered,
                 const Shot& shot, const Camera& camera, const ApertureImages& images,
                 std::string& error, int nthreads)
{
    if (shot.aov == Aov::Confidence)
        return confidence_aov(aov, image, layered, shot, camera, images, error, nthreads);
    if (shot.aov == Aov::Coc
        && !coc_aov(aov, layered, camera, shot.spread, images, shot.window, image.roi(),
                    nthreads)) {
        error = aov.geterror();
        return false;
    }
    return true;
}

/// The data channels' question before each spread, asked as their stage
/// saying how far it is ("data channels 12/134").
std::function<bool(int, int)> data_progress(const StageCallback& on_stage)
{
    return [&on_stage](int done, int total) {
        return !on_stage || on_stage(format("data channels {}/{}", done, total).c_str());
    };
}

/// finish_frame() of a deep result, from the spread on (see defocus_deep).
bool deep_frame(const Shot& shot, int frame, const ApertureImages& images,
                LayeredScene& layered, FrameResult& out, std::string& error, int nthreads)
{
    Timer timer;
    SpreadStats stats;
    DeepResult deep;
    if (!defocus_deep_freeing(deep, layered, out.camera, shot.spread, images, shot.window,
                              error, &out.layers, &stats, nthreads))
        return false;
    out.timings.emplace_back("spread and composite", stats.spread);
    out.cells = stats.cells;
    timer.lap();
    // The deep image is the largest allocation of the frame: its size is
    // known once the layers are spread, before it is made.
    double samples = 0.0;
    for (const DeepLayer& layer : deep.layers)
        samples += double(layer.pixels.size());
    const double bytes = samples * deep_sample_bytes(deep_color_type(shot, layered.spec))
                         + double(deep.window.npixels()) * deep_pixel_bytes;
    if (!shot.read.memory_limit.allows(bytes)) {
        error = shot.read.memory_limit.exceeded(
            format("a deep result of {:.0f} samples", samples), bytes);
        return false;
    }
    const ColorPlan& color = out.color;
    for (DeepLayer& layer : deep.layers) {
        if (!color.config || layer.pixels.empty())
            continue;
        // A column of the layer's samples: rows are what is run in parallel.
        ImageBuf samples(ImageSpec(1, int(layer.pixels.size()), 4, TypeFloat),
                         layer.rgba.data());
        if (!color.config->convert(samples, color.working, color.output, error, nthreads))
            return false;
    }
    out.timings.emplace_back("colour out", timer.lap());
    out.pixel_type = deep_color_type(shot, layered.spec);
    out.image = deep_buffer(std::move(deep), layered.spec, out.pixel_type, nthreads);
    out.timings.emplace_back("deep image", timer.lap());
    describe_output(out.image.specmod(), layered.spec, shot, out.camera, out.depth.kind, color,
                    frame);
    return true;
}

/// Spreads and composites the frame's layers into `out.image`, freeing
/// them as it goes unless an AOV or data channels read them after.
bool spread_frame(const Shot& shot, const ApertureImages& images, LayeredScene& layered,
                  bool data_channels, FrameResult& out, std::string& error, int nthreads)
{
    SpreadStats stats;
    const bool spread
        = shot.aov != Aov::None || data_channels
              ? defocus_layers(out.image, layered, out.camera, shot.spread, images, shot.window,
                               &out.layers, &stats, nthreads)
              : defocus_layers_freeing(out.image, layered, out.camera, shot.spread, images,
                                       shot.window, &out.layers, &stats, nthreads);
    if (!spread) {
        error = out.image.geterror();
        return false;
    }
    out.timings.emplace_back("spread and composite", stats.spread);
    out.cells = stats.cells;
    return true;
}

/// The focus map or the layer view of a frame, as the shot's output says.
bool false_colour_picture(const Shot& shot, const LayeredScene& layered, FrameResult& out,
                          std::string& error, int nthreads)
{
    if (shot.output == OutputKind::Layers) {
        out.layers = layered.reports;
        return layer_view(out.image, layered, nthreads);
    }
    if (focus_map(out.image, layered, out.camera, 8.0, nthreads))
        return true;
    error = out.image.geterror();
    return false;
}

/// A frame from its prepared layers to the image to write. Errors do not
/// name the source: the caller does.
bool finish_frame(const Shot& shot, int frame, const ApertureImages& images,
                  LayeredScene& layered, FrameResult& out, std::string& error,
                  const StageCallback& on_stage, int nthreads)
{
    const ColorPlan& color = out.color;
    const CircleOfConfusion coc(out.camera, layered.spec.roi_full());
    Timer timer;
    auto lap = [&](const char* name) { out.timings.emplace_back(name, timer.lap()); };
    if (!run_stage(on_stage, "render", error))
        return false;
    ImageBuf& image = out.image;
    if (shot.output != OutputKind::Image) {
        if (!false_colour_picture(shot, layered, out, error, nthreads))
            return false;
        lap(shot.output == OutputKind::FocusMap ? "focus map" : "layer view");
    } else {
        DataPlan plan;
        if (!read_holdout(shot, frame, layered.spec, layered.holdout, error)
            || !frame_data_plan(shot, frame, layered.spec, plan, error))
            return false;
        out.holdout = holdout_line(shot, frame, layered.holdout.get());
        out.data = plan.summary();
        const double bytes = spread_bytes(layered, shot.spread, out.camera, nthreads);
        if (!shot.read.memory_limit.allows(bytes)) {
            error = shot.read.memory_limit.exceeded(
                format("spreading {} layers with blur up to {:g} px", layered.layers.size(),
                       out.camera.max_blur_px),
                bytes);
            return false;
        }
        const int extended = extend_edges(layered, coc, shot.edge, nthreads);
        if (extended > 0)
            out.edges = format("edges: layers extended up to {} px past the data window ({}; "
                               "{} keeps them dark)",
                               extended,
                               shot.edge == EdgeMode::Extend
                                   ? mention("edge", "extend")
                                   : "the data window does not cover the blur's reach",
                               mention("edge", "black"));
        if (shot.deep)
            return deep_frame(shot, frame, images, layered, out, error, nthreads);
        if (!spread_frame(shot, images, layered, !plan.empty(), out, error, nthreads))
            return false;
        timer.lap();
        ImageBuf aov, data;
        if (!aov_channel(aov, image, layered, shot, out.camera, images, error, nthreads))
            return false;
        if (aov.initialized())
            lap(aov_name(shot.aov));
        if (!plan.empty()) {
            if (!data_channels(data, image, layered, out.camera, shot.spread, images,
                               shot.window, plan, nthreads,
                               data_progress(on_stage))) {
                error = data.geterror();
                return false;
            }
            lap("data channels");
        }
        if (color.config
            && !color.config->convert(image, color.working, color.output, error, nthreads))
            return false;
        for (const ImageBuf* extra : { &aov, &data }) {
            if (!extra->initialized())
                continue;
            ImageBuf both;
            if (!ImageBufAlgo::channel_append(both, image, *extra, {}, nthreads)) {
                error = both.geterror();
                return false;
            }
            image = std::move(both);
        }
        out.data_channels = data.initialized() ? data.nchannels() : 0;
        lap("colour out");
    }
    describe_output(image.specmod(), layered.spec, shot, out.camera, out.depth.kind, color,
                    frame);
    out.pixel_type = output_pixel_type(shot, layered.spec);
    return true;
}

}  // namespace

bool frame_spec(const Shot& shot, int frame, const ShotAssets& assets, ImageSpec& spec,
                std::string& error)
{
    ImageSpec input;
    ColorPlan color;
    if (!read_scene_spec(frame_inputs(shot, frame), frame_read_options(shot, frame), input,
                         error)
        || !plan_color(color, assets.color, assets.no_color, shot.input_space,
                       shot.output_space, input, error))
        return false;
    const ROI display(input.full_x, input.full_x + input.full_width, input.full_y,
                      input.full_y + input.full_height, 0, 1, 0, 4);
    Camera camera = camera_at(shot, frame);
    camera.pixel_aspect = header_pixel_aspect(input);
    ROI window = display;
    if (shot.output == OutputKind::Image && shot.window == OutputWindow::Input)
        window = input.roi();
    if (shot.output == OutputKind::Image && shot.window == OutputWindow::Grown) {
        // Finding the window spreads a probe as far as the largest blur
        // reaches: no further than half the largest blur past the data
        // window, with a margin for block alignment and lateral CA.
        const double reach = 0.5 * camera.max_blur_px + 64
                             + std::abs(camera.lateral_ca) * (input.full_width + input.full_height);
        const double probe_bytes =
            float_bytes((window.width() + 2 * reach) * (window.height() + 2 * reach), 4);
        if (!shot.read.memory_limit.allows(probe_bytes)) {
            error = format("{}: {}", Strutil::join(frame_inputs(shot, frame), " "),
                           shot.read.memory_limit.exceeded(
                               format("a window grown by blur up to {:g} px", camera.max_blur_px),
                               probe_bytes));
            return false;
        }
        if (!largest_grown_window(window, input, camera, shot.spread, assets.aperture, error))
            return false;
        window = roi_union(window, display);
    }
    // A host allocates what the spec says (OpenImageIO crashes on windows
    // near 100000 pixels square), so a spec is a promise the frame fits.
    const double bytes = float_bytes(std::max(window.npixels(), display.npixels()), 4);
    if (!shot.read.memory_limit.allows(bytes)) {
        error = format("{}: {}", Strutil::join(frame_inputs(shot, frame), " "),
                       shot.read.memory_limit.exceeded(
                           format("a {}x{} result", window.width(), window.height()), bytes));
        return false;
    }
    spec = shot.deep ? deep_result_spec(input, window, deep_color_type(shot, input))
                     : result_spec(input, window, output_pixel_type(shot, input));
    for (const std::string& name : aov_channel_names(output_aov(shot))) {
        spec.nchannels += 1;
        spec.channelnames.push_back(name);
    }
    DataPlan plan;
    if (!frame_data_plan(shot, frame, input, plan, error))
        return false;
    if (!plan.empty() && shot.output == OutputKind::Image) {
        // Data is written as float: IDs are float bits, P is far from 0.
        spec.channelformats.assign(spec.nchannels, spec.format);
        for (const std::string& name : plan.output_channels()) {
            spec.channelnames.push_back(name);
            spec.channelformats.push_back(TypeFloat);
        }
        spec.nchannels = int(spec.channelnames.size());
        // A host that writes every channel as one type (oiiotool) takes the
        // spec's format: float keeps the IDs whole.
        spec.format = TypeFloat;
    }
    describe_output(spec, input, shot, camera, frame_depth_kind(shot, input).kind, color, frame);
    // Focusing at a pixel measures the focus from the pixels.
    if (!shot.focus_at.empty())
        spec.erase_attribute("defocus:focusDistance");
    return true;
}

namespace {

/// render_frame() and render_scene(): `prepare` makes the layers.
template<typename Prepare>
bool render(const Shot& shot, int frame, const ShotAssets& assets, FrameResult& result,
            std::string& error, const StageCallback& on_stage, int nthreads,
            Prepare&& prepare)
{
    result = FrameResult();
    try {
        LayeredScene layered;
        if (!prepare(layered))
            return false;  // named there
        if (finish_frame(shot, frame, assets.aperture, layered, result, error, on_stage,
                         nthreads))
            return true;
    } catch (const std::bad_alloc&) {
        error = "out of memory";
    }
    if (!result.source.empty())
        error = result.source + ": " + error;
    return false;
}

}  // namespace

bool render_frame(const Shot& shot, int frame, const ShotAssets& assets,
                  FrameResult& result, std::string& error, const StageCallback& on_stage,
                  int nthreads)
{
    return render(shot, frame, assets, result, error, on_stage, nthreads,
                  [&](LayeredScene& layered) {
                      return prepare_layers(shot, frame, assets, layered, result, error,
                                            on_stage, nthreads);
                  });
}

bool render_scene(Scene&& scene, const Shot& shot, int frame, const ShotAssets& assets,
                  FrameResult& result, std::string& error, const StageCallback& on_stage,
                  int nthreads)
{
    return render(shot, frame, assets, result, error, on_stage, nthreads,
                  [&](LayeredScene& layered) {
                      return prepare_layers(std::move(scene), shot, frame, assets, layered,
                                            result, error, on_stage, nthreads);
                  });
}

}  // namespace defocus
