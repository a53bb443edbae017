#include <defocus/run_shot.h>

#include <atomic>

#include <OpenImageIO/timer.h>

#include <defocus/io/frames.h>
#include <defocus/io/image_output.h>
#include <defocus/io/scene_io.h>
#include <defocus/io/settings_hash.h>
#include <defocus/shot/setting_words.h>
#include <defocus/stage_timeline.h>

namespace defocus {

using namespace OIIO;

namespace {

/// `frames` less those whose output is written with the shot's settings,
/// each noted in `plan`.
std::vector<int> without_existing(const Shot& shot, const RunRequest& request,
                                  const std::vector<int>& frames, RunPlan& plan)
{
    std::vector<int> to_render;
    for (int frame : frames) {
        const std::string output = frame_path(request.output, frame);
        std::string why;
        if (written_with_settings(output, settings_hash(shot, frame), why)) {
            plan.skipped.push_back({ frame, output, "" });
            continue;
        }
        if (why != "does not exist")
            plan.again.push_back({ frame, output, why });
        to_render.push_back(frame);
    }
    return to_render;
}

/// Every file of `plan` writable, the side files apart from the images.
bool check_outputs(const Shot& shot, const RunRequest& request, const RunPlan& plan,
                   std::string& error)
{
    std::vector<std::string> named;
    if (const Aov aov = output_aov(shot); aov != Aov::None)
        named.push_back(mention("aov", aov_name(aov)));
    if (shot.data_channels != Shot().data_channels)
        named.push_back(mention("data-channels", shot.data_channels));
    const std::string named_channels = Strutil::join(named, " and ");
    for (size_t i = 0; i < plan.outputs.size(); ++i) {
        if (!check_output(plan.outputs[i], shot.compression, error, shot.deep, named_channels))
            return false;
        for (size_t s = 0; s < request.sides.size(); ++s) {
            const std::vector<std::string>& files = plan.side_files[s];
            if (files.empty())
                continue;
            if (!check_output(files[i], request.sides[s].compression, error)) {
                error = request.sides[s].option + " " + error;
                return false;
            }
            if (same_path(plan.outputs[i], files[i])) {
                error = Strutil::fmt::format("{}: {} and {} name the same file", plan.outputs[i],
                                             request.output_option, request.sides[s].option);
                return false;
            }
        }
    }
    return true;
}

/// The outputs of `plan.frames`, through the request's patterns.
bool name_outputs(const RunRequest& request, RunPlan& plan, std::string& error)
{
    if (!frame_outputs(request.output_option, request.output, plan.frames, plan.outputs, error))
        return false;
    plan.side_files.resize(request.sides.size());
    for (size_t s = 0; s < request.sides.size(); ++s)
        if (!frame_outputs(request.sides[s].option, request.sides[s].pattern, plan.frames,
                           plan.side_files[s], error))
            return false;
    return true;
}

}  // namespace

bool plan_run(const Shot& shot, const RunRequest& request, RunPlan& plan, std::string& error)
{
    plan = RunPlan();
    plan.frames = request.frames;
    if (plan.frames.empty() && !shot_frames(shot, plan.frames, error, &plan.missing))
        return false;
    plan.shot_frame_count = plan.frames.size();
    // The patterns must suit the whole shot, whatever part of it this run
    // renders.
    if (!name_outputs(request, plan, error))
        return false;
    if (request.chunks > 0)
        plan.frames = chunk_frames(plan.frames, request.chunk, request.chunks);
    if (request.skip_existing)
        plan.frames = without_existing(shot, request, plan.frames, plan);
    if (plan.frames.size() != plan.shot_frame_count && !name_outputs(request, plan, error))
        return false;
    // Refused before any frame is rendered, not after each.
    if (!check_outputs(shot, request, plan, error))
        return false;
    std::vector<std::string> read = files_read(shot, plan.frames), written = plan.outputs;
    read.insert(read.end(), request.also_read.begin(), request.also_read.end());
    for (const std::vector<std::string>& files : plan.side_files)
        written.insert(written.end(), files.begin(), files.end());
    written.insert(written.end(), request.also_written.begin(), request.also_written.end());
    return check_overwrites(read, written, error);
}

ScheduleResult run_plan(const Shot& shot, const ShotAssets& assets, const RunPlan& plan,
                        const RunRequest& request, const RunCallbacks& callbacks,
                        bool* cancelled)
{
    std::atomic<bool> stop { false };
    StageTimeline timeline;
    auto render_one = [&](int i) {
        if (stop)
            return false;
        const int frame = plan.frames[i];
        auto stage = [&](const char* name) {
            if (name)
                timeline.enter(frame, name);
            if (!stop && (!callbacks.stage || callbacks.stage(frame, name)))
                return true;
            stop = true;
            return false;
        };
        Timer timer;
        FrameResult result;
        // Each thread renders into the image it wrote last: a sequence's
        // frames skip a new frame's fresh pages (see defocus_layers). The
        // first frame's thread renders no other (see run_frames), so its
        // image is not kept past it: the memory of the frames in flight
        // stays theirs.
        thread_local ImageBuf last_image;
        result.image.swap(last_image);
        std::string error;
        const bool ok = [&] {
            if (!render_frame(shot, frame, assets, result, error, stage, request.threads)
                || !stage("write"))
                return false;
            Timer write_timer;
            for (size_t s = 0; s < request.sides.size(); ++s)
                if (!plan.side_files[s].empty()
                    && !request.sides[s].write(result, plan.side_files[s][i], error))
                    return false;
            if (!write_image_atomic(result.image, plan.outputs[i], result.pixel_type, "", error,
                                    result.data_channels, &result.pixel_type))
                return false;
            result.timings.emplace_back("write", write_timer());
            return true;
        }();
        result.overlap = timeline.finish(frame);
        if (ok && callbacks.written)
            callbacks.written(frame, plan.outputs[i], result, timer());
        else if (!ok && !stop && callbacks.failed)
            callbacks.failed(frame, error);
        if (i > 0)
            last_image.swap(result.image);
        return ok;
    };
    const ScheduleResult run = run_frames(
        int(plan.frames.size()), request.threads, size_t(shot.read.memory_limit.for_frames()),
        request.stop_on_error, render_one,
        [&](int i) {
            return declared_bytes(frame_inputs(shot, plan.frames[i]), shot.read.memory_limit);
        });
    if (cancelled)
        *cancelled = stop;
    return run;
}

}  // namespace defocus
