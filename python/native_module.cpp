// defocus._defocus: the library's shots, frames and sequences for the
// Python package beside it (defocus/__init__.py), which turns Python values
// into the settings' text and back and checks arrays before they get here.
// Files are written through the render service (run_shot.h), as the CLI
// writes them.
//
// Every render runs on a thread of its own with the GIL released; the
// calling thread waits for it and checks Python's signals, so Ctrl-C
// cancels the render at its next stage and raises KeyboardInterrupt.
#include <atomic>
#include <exception>
#include <mutex>
#include <optional>
#include <unordered_map>

#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <OpenImageIO/strutil.h>

#include <defocus/frame_scheduler.h>
#include <defocus/render_frame.h>
#include <defocus/run_shot.h>
#include <defocus/version.h>

#include "arrays.h"
#include "cancellable.h"
#include "python_errors.h"
#include "shot_binding.h"

namespace py = pybind11;
using namespace defocus;
using namespace defocus_python;
using OIIO::ROI;
using OIIO::Strutil::fmt::format;

namespace {

ShotAssets read_assets(const Shot& shot)
{
    ShotAssets assets;
    std::string error;
    check(check_shot(shot, error) && read_shot_assets(shot, assets, error), error);
    return assets;
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
    // A plan's frames are distinct; a search per failure was quadratic in
    // a long sequence that fails throughout.
    std::unordered_map<int, size_t> index_of;
    for (size_t i = 0; i < plan.frames.size(); ++i)
        index_of.emplace(plan.frames[i], i);
    std::exception_ptr written_failure;
    std::mutex mutex;
    ScheduleResult run;
    run_cancellable([&](const std::atomic<bool>& cancelled) {
        std::atomic<bool> stop { false };
        RunCallbacks callbacks;
        callbacks.stage = [&](int, const char*) { return !cancelled && !stop; };
        callbacks.failed = [&](int frame, const std::string& error) {
            errors[index_of.at(frame)] = error;
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
    return layer_arrays(layered.layers, window);
}

}  // namespace

PYBIND11_MODULE(_defocus, m)
{
    m.doc() = "defocus's native core; use the defocus package, which wraps it.";
    m.attr("__version__") = version();
    py::register_exception<Error>(m, "Error", PyExc_RuntimeError);
    bind_shot(m);

    m.def("render", &render);
    m.def("focus_map", &focus_map);
    m.def("render_to_file", &render_to_file);
    m.def("render_sequence", &render_sequence);
    m.def("render_layers", &render_layers);
    m.def("decompose", &decompose);
}
