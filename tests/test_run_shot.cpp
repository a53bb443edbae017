// The render service every front end adapts: planning, checks, cancelling,
// sequences.
#include <catch2/catch.hpp>

#include <chrono>
#include <cstdio>
#include <map>
#include <thread>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>

#include <defocus/run_shot.h>
#include <defocus/stage_timeline.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;

namespace {

Shot example_shot()
{
    Shot shot;
    shot.inputs = { example_scene() };
    std::string error;
    REQUIRE(set_shot_setting(shot, "focus", "4", error));
    return shot;
}

struct Reports {
    std::vector<std::string> written, failed, stages;
};

RunCallbacks recording(Reports& reports, const char* cancel_at = nullptr)
{
    RunCallbacks callbacks;
    callbacks.stage = [&reports, cancel_at](int, const char* stage) {
        reports.stages.push_back(stage);
        return !cancel_at || std::string(stage) != cancel_at;
    };
    callbacks.written = [&reports](int, const std::string& output, const FrameResult& result,
                                   double) {
        reports.written.push_back(output);
        CHECK(result.timings.back().first == "write");
    };
    callbacks.failed = [&reports](int, const std::string& error) {
        reports.failed.push_back(error);
    };
    return callbacks;
}

}  // namespace

TEST_CASE("a run writes each planned frame once, and a cancelled run writes nothing and fails none")
{
    const Shot shot = example_shot();
    ShotAssets assets;
    std::string error;
    REQUIRE(read_shot_assets(shot, assets, error));
    RunRequest request;
    request.output = scratch_dir("run_shot") + "/out.exr";
    OIIO::Filesystem::remove(request.output);
    RunPlan plan;
    REQUIRE(plan_run(shot, request, plan, error));
    REQUIRE(plan.outputs == std::vector<std::string> { request.output });

    Reports cancelled;
    bool was_cancelled = false;
    ScheduleResult run = run_plan(shot, assets, plan, request, recording(cancelled, "slice"),
                                  &was_cancelled);
    CHECK(was_cancelled);
    CHECK(run.failed.size() == 1);
    CHECK(cancelled.stages == std::vector<std::string> { "read", "colour", "slice" });
    CHECK(cancelled.written.empty());
    CHECK(cancelled.failed.empty());
    CHECK_FALSE(OIIO::Filesystem::exists(request.output));

    Reports done;
    run = run_plan(shot, assets, plan, request, recording(done), &was_cancelled);
    CHECK_FALSE(was_cancelled);
    CHECK(run.failed.empty());
    CHECK(done.written == plan.outputs);
    CHECK(done.stages.back() == "write");
    CHECK(OIIO::Filesystem::exists(request.output));

    // Written with these settings: left out, and said so.
    request.skip_existing = true;
    REQUIRE(plan_run(shot, request, plan, error));
    CHECK(plan.frames.empty());
    REQUIRE(plan.skipped.size() == 1);
    CHECK(plan.skipped[0].output == request.output);
}

TEST_CASE("a plan refuses, before any work, an output that is an input or another output")
{
    const Shot shot = example_shot();
    RunRequest request;
    RunPlan plan;
    std::string error;
    request.output = shot.inputs[0];
    CHECK_FALSE(plan_run(shot, request, plan, error));
    CHECK(OIIO::Strutil::contains(error, shot.inputs[0]));
    CHECK(OIIO::Strutil::contains(error, "would overwrite"));

    request.output = scratch_dir("run_shot") + "/image.exr";
    request.also_read = { scratch_dir("run_shot") + "/image.exr" };
    OIIO::Filesystem::write_text_file(request.also_read[0], "a scene file");
    CHECK_FALSE(plan_run(shot, request, plan, error));
    CHECK(OIIO::Strutil::contains(error, "would overwrite"));

    request.also_read.clear();
    request.sides.push_back({ "--preview", request.output, "", {} });
    CHECK_FALSE(plan_run(shot, request, plan, error));
    CHECK(OIIO::Strutil::contains(error, "name the same file"));
}

TEST_CASE("a sequence: keyframes per frame, each frame's metadata, and frames sharing a thread's "
          "image rendered as alone")
{
    const std::string dir = scratch_dir("run_shot_sequence");
    for (int f : { 1001, 1002, 1003 })
        REQUIRE(OIIO::Filesystem::copy(example_scene(), OIIO::Strutil::fmt::format(
                                                            "{}/in.{}.exr", dir, f)));
    const Shot shot = shot_with({ dir + "/in.#.exr" }, { { "focal", "50" },
                                                         { "fstop", "1001:2,1003:4" },
                                                         { "focus", "1001:1,1003:4" } });
    ShotAssets assets;
    std::string error;
    REQUIRE(read_shot_assets(shot, assets, error));
    RunRequest request;
    request.output = dir + "/out.#.exr";
    request.threads = 1;  // one thread renders every frame into one image
    RunPlan plan;
    REQUIRE(plan_run(shot, request, plan, error));
    CHECK(plan.frames == std::vector<int> { 1001, 1002, 1003 });  // the input's own frames
    std::map<int, OIIO::ImageSpec> written;
    OIIO::ImageBuf last_frame;
    RunCallbacks callbacks;
    callbacks.written = [&](int frame, const std::string&, const FrameResult& result, double) {
        written[frame] = result.image.spec();
        CHECK(result.overlap.empty());  // one thread: one frame at a time
        if (frame == 1003)
            last_frame.copy(result.image);
    };
    REQUIRE(run_plan(shot, assets, plan, request, callbacks).failed.empty());
    REQUIRE(written.size() == 3);
    // Focus linear in 1/z: 1/z at 1002 is halfway between 1/1 and 1/4.
    CHECK(written[1001].get_float_attribute("defocus:focusDistance") == 1.0f);
    CHECK(written[1002].get_float_attribute("defocus:focusDistance") == Approx(1.6f));
    CHECK(written[1003].get_float_attribute("defocus:focusDistance") == 4.0f);
    CHECK(written[1002].get_float_attribute("defocus:fNumber")
          == Approx(1.0 / (0.5 / 2 + 0.5 / 4)));
    CHECK(written[1002].get_int_attribute("defocus:frame") == 1002);

    // Frame 1003, rendered into the image an earlier frame left, comes out
    // as rendered alone.
    const OIIO::ImageBuf alone = rendered(dir + "/in.1003.exr", { { "focal", "50" },
                                                                  { "fstop", "4" },
                                                                  { "focus", "4" } });
    CHECK(OIIO::ImageBufAlgo::compare(last_frame, alone, 0.0f, 0.0f).maxerror == 0.0);
}

TEST_CASE("a long stage saying how far it is stays one stage")
{
    CHECK(stage_of("data channels 12/134") == "data channels");
    CHECK(stage_of("data channels") == "data channels");
    CHECK(stage_of("read") == "read");
    CHECK(stage_of("render 3/") == "render 3/");
    CHECK(stage_of("take 2") == "take 2");
    StageTimeline timeline;
    timeline.enter(2, "read");
    for (const char* stage : { "render", "data channels 0/3", "data channels 1/3",
                               "data channels 2/3" }) {
        timeline.enter(1, stage);
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    const std::string report = timeline.finish(1);
    INFO(report);
    CHECK(OIIO::Strutil::contains(report, "data channels 0.0"));
    CHECK_FALSE(OIIO::Strutil::contains(report, "/3"));
    CHECK(std::count(report.begin(), report.end(), ',') <= 1);
}

TEST_CASE("the stages of frames side by side, and how long each overlapped others (-v)")
{
    using std::this_thread::sleep_for;
    const auto step = std::chrono::milliseconds(40);
    StageTimeline timeline;
    // Frame 1 reads alone, then beside frame 2's read; it renders beside
    // frame 2's read, then alone; frame 2 renders after it is done.
    timeline.enter(1, "read");
    sleep_for(step);
    timeline.enter(2, "read");
    sleep_for(step);
    timeline.enter(1, "render");
    sleep_for(step);
    timeline.enter(2, "render");
    sleep_for(step);
    const std::string first = timeline.finish(1);
    sleep_for(step);
    const std::string second = timeline.finish(2);
    INFO(first);
    INFO(second);
    CHECK(OIIO::Strutil::starts_with(first, "read 0.0"));
    CHECK(OIIO::Strutil::contains(first, "s beside 2 read), render 0."));
    CHECK(OIIO::Strutil::contains(first, "s beside 2 read, 2 render)"));
    CHECK(OIIO::Strutil::contains(second, "s beside 1 read, 1 render), render 0."));
    CHECK(OIIO::Strutil::contains(second, "s beside 1 render)"));
    // The seconds beside: frame 2's render overlapped frame 1 for one step
    // of its two.
    const size_t at = second.rfind("render ");
    float took = 0.0f, beside = 0.0f;
    REQUIRE(std::sscanf(second.c_str() + at, "render %f s (%f s beside", &took, &beside) == 2);
    CHECK(took >= 0.08f);
    CHECK(beside >= 0.04f);
    CHECK(beside < took - 0.035f);

    // A frame alone afterwards met nobody: the others' stages are gone.
    timeline.enter(3, "read");
    sleep_for(step);
    CHECK(timeline.finish(3).empty());
}
