// defocus._defocus: the library's shots, frames and sequences for the
// Python package beside it (defocus/__init__.py), which turns Python values
// into the settings' text and back and checks arrays before they get here.
//
// Every render runs on a thread of its own with the GIL released; the
// calling thread waits for it and checks Python's signals, so Ctrl-C
// cancels the render at its next stage and raises KeyboardInterrupt.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <optional>
#include <regex>
#include <stdexcept>
#include <thread>

#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>

#include <defocus/error_line.h>
#include <defocus/frame_scheduler.h>
#include <defocus/io/frames.h>
#include <defocus/io/image_output.h>
#include <defocus/io/scene_io.h>
#include <defocus/io/settings_hash.h>
#include <defocus/render_frame.h>
#include <defocus/run_shot.h>
#include <defocus/io/shot_file.h>
#include <defocus/version.h>

namespace py = pybind11;
using namespace defocus;
using OIIO::ImageBuf;
using OIIO::ImageSpec;
using OIIO::ROI;
using OIIO::TypeFloat;
namespace Strutil = OIIO::Strutil;
using OIIO::Strutil::fmt::format;

namespace {

/// A setting's value as a Python literal: a number, a pixel (x, y), a
/// bool, or quoted text.
std::string python_literal(const ShotSetting& setting, const std::string& value)
{
    if (setting.kind == ShotValueKind::Point)
        return "(" + Strutil::replace(value, ",", ", ") + ")";
    if (setting.kind == ShotValueKind::Switch)
        return value == "on" ? "True" : "False";
    return Strutil::string_is<double>(value) ? value : "\"" + value + "\"";
}

/// The library's message with each setting's option named as its Python
/// keyword: "--focus-at X,Y" reads "focus_at=X,Y", "--aperture polygon"
/// reads 'aperture="polygon"'. A word after an option is its value when
/// the setting takes it, or a placeholder when in capitals; else the
/// option stands alone ("--aov applies ..." reads "aov applies ...").
std::string python_words(const std::string& message)
{
    static const std::regex option(R"(--([a-z][a-z0-9-]*)( ([A-Za-z0-9:,.+-]*[A-Za-z0-9]))?)");
    std::string out;
    auto last = message.cbegin();
    for (std::sregex_iterator it(message.begin(), message.end(), option), end; it != end;
         ++it) {
        const std::smatch& m = *it;
        const auto setting = std::find_if(shot_settings().begin(), shot_settings().end(),
                                          [&](const ShotSetting& s) { return m[1] == s.name; });
        if (setting == shot_settings().end())
            continue;
        out.append(last, m[0].first);
        out += Strutil::replace(m[1].str(), "-", "_", true);
        const std::string word = m[3];
        Shot scratch;
        std::string ignored;
        if (m[2].matched && set_shot_setting(scratch, setting->name, word, ignored))
            out += "=" + python_literal(*setting, word);
        else if (m[2].matched && Strutil::upper(word) == word)
            out += "=" + word;
        else
            out += m[2].str();
        last = m[0].second;
    }
    out.append(last, message.cend());
    return out;
}

/// Raised as defocus.Error, with the one-line message the CLI prints, the
/// settings named as Python keywords.
struct Error : std::runtime_error {
    explicit Error(const std::string& message)
        : std::runtime_error(error_line(python_words(message)))
    {
    }
};

void check(bool ok, const std::string& error)
{
    if (!ok)
        throw Error(error);
}

/// Runs work(cancelled) on its own thread while this one, GIL released,
/// waits and checks Python's signals every 50 ms. A signal handler that
/// raises (Ctrl-C: KeyboardInterrupt) sets `cancelled`; its exception is
/// raised once the work has stopped, so that no file is half written.
template<typename Work>
void run_cancellable(Work&& work)
{
    std::atomic<bool> cancelled { false };
    std::exception_ptr failure;
    std::mutex mutex;
    std::condition_variable finished_cv;
    bool finished = false;
    std::thread worker([&] {
        try {
            work(cancelled);
        } catch (...) {
            failure = std::current_exception();
        }
        std::lock_guard<std::mutex> lock(mutex);
        finished = true;
        finished_cv.notify_all();
    });
    bool interrupted = false;
    for (;;) {
        {
            py::gil_scoped_release release;
            std::unique_lock<std::mutex> lock(mutex);
            if (finished_cv.wait_for(lock, std::chrono::milliseconds(50),
                                     [&] { return finished; }))
                break;
        }
        if (!interrupted && PyErr_CheckSignals() != 0) {
            interrupted = true;
            cancelled = true;
        }
    }
    worker.join();
    if (interrupted)
        throw py::error_already_set();
    if (failure)
        std::rethrow_exception(failure);
}

/// A stage callback that stops the render once cancelled.
StageCallback stop_when(const std::atomic<bool>& cancelled)
{
    return [&cancelled](const char*) { return !cancelled; };
}

ShotAssets read_assets(const Shot& shot)
{
    ShotAssets assets;
    std::string error;
    check(check_shot(shot, error) && read_shot_assets(shot, assets, error), error);
    return assets;
}

/// The frame to render: the one given, else the shot's first.
int frame_or_first(const Shot& shot, std::optional<int> frame)
{
    if (frame)
        return *frame;
    std::vector<int> frames;
    std::string error;
    check(shot_frames(shot, frames, error), error);
    return frames.front();
}

/// The image's data window (or display window, zero outside the data) as
/// float32 rows of pixels, and its spec as OpenImageIO's XML.
py::tuple image_result(const ImageBuf& image, bool crop)
{
    const ImageSpec& spec = image.spec();
    ROI roi = image.roi();
    if (crop)
        roi = ROI(spec.full_x, spec.full_x + spec.full_width, spec.full_y,
                  spec.full_y + spec.full_height, 0, 1, 0, spec.nchannels);
    py::array_t<float> pixels({ roi.height(), roi.width(), roi.nchannels() });
    float* data = pixels.mutable_data();
    {
        py::gil_scoped_release release;
        image.get_pixels(roi, TypeFloat, data);
    }
    ImageSpec described = spec;
    described.x = roi.xbegin, described.y = roi.ybegin;
    described.width = roi.width(), described.height = roi.height();
    return py::make_tuple(pixels, described.to_xml());
}

/// Renders frame `at` of a shot, cancellably.
FrameResult render_one(const Shot& shot, int at)
{
    const ShotAssets assets = read_assets(shot);
    FrameResult result;
    run_cancellable([&](const std::atomic<bool>& cancelled) {
        std::string error;
        check(render_frame(shot, at, assets, result, error, stop_when(cancelled)), error);
    });
    return result;
}

py::tuple render(const Shot& shot, std::optional<int> frame, bool crop)
{
    return image_result(render_one(shot, frame_or_first(shot, frame)).image, crop);
}

py::tuple focus_map(const Shot& shot, std::optional<int> frame, bool crop)
{
    Shot map = shot;
    map.output = OutputKind::FocusMap;
    return image_result(render_one(map, frame_or_first(map, frame)).image, crop);
}

/// Called with the GIL held as each frame is written: (frame, path).
using WrittenCallback = std::function<void(int, std::string)>;

/// Runs a planned shot (run_plan), cancellably; `written` may raise, which
/// stops the run and is raised once it has stopped. Returns each failed
/// frame's error, by index in the plan.
std::pair<ScheduleResult, std::vector<std::string>> run_cancellable_plan(
    const Shot& shot, const RunPlan& plan, const RunRequest& request,
    const WrittenCallback& written)
{
    const ShotAssets assets = read_assets(shot);
    std::vector<std::string> errors(plan.frames.size());
    std::exception_ptr written_failure;
    std::mutex mutex;
    ScheduleResult run;
    run_cancellable([&](const std::atomic<bool>& cancelled) {
        std::atomic<bool> stop { false };
        RunCallbacks callbacks;
        callbacks.stage = [&](int, const char*) { return !cancelled && !stop; };
        callbacks.failed = [&](int frame, const std::string& error) {
            const auto at = std::find(plan.frames.begin(), plan.frames.end(), frame);
            errors[at - plan.frames.begin()] = error;
        };
        if (written)
            callbacks.written = [&](int frame, const std::string& output, const FrameResult&,
                                    double) {
                py::gil_scoped_acquire gil;
                try {
                    written(frame, output);
                } catch (...) {
                    std::lock_guard<std::mutex> lock(mutex);
                    if (!written_failure)
                        written_failure = std::current_exception();
                    stop = true;
                }
            };
        run = run_plan(shot, assets, plan, request, callbacks);
    });
    if (written_failure)
        std::rethrow_exception(written_failure);
    return { run, errors };
}

void render_to_file(const Shot& shot, const std::string& path, std::optional<int> frame)
{
    RunRequest request;
    request.output = path;
    request.frames = { frame_or_first(shot, frame) };
    RunPlan plan;
    std::string error;
    check(plan_run(shot, request, plan, error), error);
    const auto [run, errors] = run_cancellable_plan(shot, plan, request, {});
    check(run.failed.empty(), errors[0]);
}

/// Renders frames side by side as the CLI does (run_plan), writing each
/// through `pattern`; progress(frame, path) is called as each is written.
/// Bad frames are reported together once the others are written.
std::vector<std::string> render_sequence(const Shot& shot, const std::string& pattern,
                                         std::optional<std::vector<int>> frames_given,
                                         const WrittenCallback& progress, int threads,
                                         bool stop_on_error)
{
    check(!frames_given || !frames_given->empty(), "render_sequence: no frames to render");
    RunRequest request;
    request.output = pattern;
    if (frames_given)
        request.frames = *frames_given;
    request.threads = threads;
    request.stop_on_error = stop_on_error;
    RunPlan plan;
    std::string error;
    check(plan_run(shot, request, plan, error), error);
    const auto [run, errors] = run_cancellable_plan(shot, plan, request, progress);
    if (!run.failed.empty()) {
        std::string summary = frames_written(run, plan.frames);
        for (int i : run.failed)
            if (!errors[i].empty())
                summary += format("; frame {}: {}", plan.frames[i], errors[i]);
        throw Error(summary);
    }
    return plan.outputs;
}

/// Where arrays lie: the data window's origin (x, y) and the display
/// window (x, y, width, height), as OpenImageIO's ImageSpec has them.
using Windows = std::tuple<int, int, int, int, int, int>;

/// `spec` placed at the windows.
void place(ImageSpec& spec, const Windows& windows)
{
    std::tie(spec.x, spec.y, spec.full_x, spec.full_y, spec.full_width, spec.full_height) =
        windows;
}

/// The camera values `frame` of a shot renders with (frame_camera), by
/// their Python names: camera_from_file's header values included, the
/// keyframes taken at the frame.
py::dict resolved_camera(const Shot& shot, std::optional<int> frame)
{
    const int at = frame_or_first(shot, frame);
    Camera camera;
    CameraOrigins origins;
    std::string error;
    bool found;
    {
        py::gil_scoped_release release;
        found = frame_camera(shot, at, camera, origins, error);
    }
    check(found, error);
    auto pixel = [](const std::optional<Imath::V2d>& p) -> py::object {
        return p ? py::object(py::make_tuple(p->x, p->y)) : py::none();
    };
    py::dict values;
    values["focal"]          = camera.focal_length_mm;
    values["fstop"]          = camera.fstop;
    values["focus"]          = camera.focus_distance;
    values["sensor"]         = camera.sensor_width_mm;
    values["focus_at"]       = pixel(camera.focus_pixel);
    values["focus_tilt"]     = py::make_tuple(camera.tilt_deg[0], camera.tilt_deg[1]);
    values["optical_centre"] = pixel(camera.axis_pixel);
    return values;
}

/// An ImageBuf of `channels` float channels from C-contiguous float32
/// pixels (checked by the Python side), placed at the windows.
ImageBuf buffer(const py::array_t<float, py::array::c_style>& pixels,
                std::vector<std::string> names, const Windows& windows)
{
    const int height = int(pixels.shape(0)), width = int(pixels.shape(1));
    ImageSpec spec(width, height, int(names.size()), TypeFloat);
    place(spec, windows);
    spec.channelnames = std::move(names);
    if (spec.nchannels == 4)
        spec.alpha_channel = 3;
    else
        spec.z_channel = 0;
    ImageBuf buf(spec);
    buf.set_pixels(buf.roi(), TypeFloat, pixels.data());
    return buf;
}

/// Layers from Python: (name, RGBA, Z), checked there.
using ArrayLayers = std::vector<std::tuple<std::string, py::array_t<float, py::array::c_style>,
                                           py::array_t<float, py::array::c_style>>>;

/// A scene in memory, named `source` in messages. One render is flat and
/// is cut into layers, as the CLI cuts a file of one part; several are
/// layers given as such.
Scene array_scene(const ArrayLayers& layers, const Windows& windows, const char* source)
{
    Scene scene;
    scene.source = source;
    const bool flat = layers.size() == 1;
    for (const auto& [name, rgba, z] : layers) {
        Layer layer { name, buffer(rgba, { "R", "G", "B", "A" }, windows),
                      buffer(z, { "Z" }, windows) };
        (flat ? scene.flat : scene.layers).push_back(std::move(layer));
    }
    const ImageSpec& first = (flat ? scene.flat : scene.layers).front().color.spec();
    scene.spec = ImageSpec(first.width, first.height, 5, TypeFloat);
    place(scene.spec, windows);
    scene.spec.channelnames = { "R", "G", "B", "A", "Z" };
    scene.spec.alpha_channel = 3;
    scene.spec.z_channel = 4;
    return scene;
}

/// `shot` with the in-memory scene as its input, so that it checks.
Shot with_input(const Shot& settings, const Scene& scene)
{
    Shot shot = settings;
    shot.inputs = { scene.source };
    return shot;
}

py::tuple render_layers(const ArrayLayers& layers, const Windows& windows, const Shot& settings,
                        std::optional<int> frame, bool crop)
{
    Scene scene = array_scene(layers, windows, "render_layers()");
    const Shot shot = with_input(settings, scene);
    const ShotAssets assets = read_assets(shot);
    const int at = frame ? *frame : 1;
    FrameResult result;
    run_cancellable([&](const std::atomic<bool>& cancelled) {
        std::string error;
        check(render_scene(std::move(scene), shot, at, assets, result, error,
                           stop_when(cancelled)),
              error);
    });
    return image_result(result.image, crop);
}

/// The layers a flat render is cut into, back to front: (name, RGBA, Z)
/// over the render's window, scene-linear.
std::vector<py::tuple> decompose(const ArrayLayers& render, const Windows& windows,
                                 const Shot& settings, std::optional<int> frame)
{
    Scene scene = array_scene(render, windows, "decompose()");
    const Shot shot = with_input(settings, scene);
    const ROI window = scene.spec.roi();
    const ShotAssets assets = read_assets(shot);
    const int at = frame ? *frame : 1;
    LayeredScene layered;
    run_cancellable([&](const std::atomic<bool>& cancelled) {
        FrameResult result;
        std::string error;
        check(prepare_layers(std::move(scene), shot, at, assets, layered, result, error,
                             stop_when(cancelled)),
              error);
    });
    std::vector<py::tuple> out;
    for (const Layer& layer : layered.layers) {
        py::array_t<float> rgba({ window.height(), window.width(), 4 });
        py::array_t<float> z({ window.height(), window.width() });
        ROI color = window, depth = window;
        color.chend = 4, depth.chend = 1;
        layer.color.get_pixels(color, TypeFloat, rgba.mutable_data());
        layer.depth.get_pixels(depth, TypeFloat, z.mutable_data());
        out.push_back(py::make_tuple(layer.name, rgba, z));
    }
    return out;
}

}  // namespace

PYBIND11_MODULE(_defocus, m)
{
    m.doc() = "defocus's native core; use the defocus package, which wraps it.";
    m.attr("__version__") = version();
    py::register_exception<Error>(m, "Error", PyExc_RuntimeError);

    py::class_<Shot>(m, "NativeShot")
        .def(py::init<>())
        .def(py::init<const Shot&>())
        .def_readwrite("inputs", &Shot::inputs)
        .def("get", [](const Shot& shot, const std::string& name) {
            return shot_setting(shot, name);
        })
        .def("set", [](Shot& shot, const std::string& name, const std::string& value,
                       const std::string& label) {
            std::string error;
            check(set_shot_setting(shot, name, value, error, label), error);
        })
        .def("is_given", [](const Shot& shot, const std::string& name) {
            return is_given(shot, name);
        })
        .def("check", [](const Shot& shot) {
            std::string error;
            check(check_shot(shot, error), error);
        })
        .def("frames", [](const Shot& shot) {
            std::vector<int> frames;
            std::string error;
            check(shot_frames(shot, frames, error), error);
            return frames;
        })
        .def("resolved_camera", &resolved_camera)
        .def("settings_hash", [](const Shot& shot, int frame) {
            return settings_hash(shot, frame);
        })
        .def("to_json", [](const Shot& shot, const std::string& directory) {
            return shot_to_json(shot, directory);
        })
        .def("save", [](const Shot& shot, const std::string& path) {
            std::string error;
            check(save_shot(shot, path, error), error);
        });
    m.def("load_shot", [](const std::string& path) {
        Shot shot;
        std::string error;
        check(load_shot(path, shot, error), error);
        return shot;
    });
    m.def("settings", [] {
        std::vector<py::tuple> list;
        for (const ShotSetting& s : shot_settings())
            list.push_back(py::make_tuple(s.name, s.section, s.key, int(s.kind)));
        return list;
    });
    m.def("frame_path", &frame_path);
    m.def("chunk_frames", &chunk_frames);
    m.def("written_with_settings", [](const std::string& path, const std::string& hash) {
        std::string why;
        const bool current = written_with_settings(path, hash, why);
        return py::make_tuple(current, why);
    });
    m.def("write_text_atomic", [](const std::string& path, const std::string& text) {
        std::string error;
        check(write_text_atomic(path, text, error), error);
    });
    m.def("render", &render);
    m.def("focus_map", &focus_map);
    m.def("render_to_file", &render_to_file);
    m.def("render_sequence", &render_sequence);
    m.def("render_layers", &render_layers);
    m.def("decompose", &decompose);
}
