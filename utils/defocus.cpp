// defocus: depth of field for layered scenes and EXR sequences, in the
// style of oiiotool. Options and .dof scene files make a shot (shot.h);
// the render service (run_shot.h) plans, renders and writes its frames.
#include <unistd.h>

#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include <OpenImageIO/argparse.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include <defocus/error_line.h>
#include <defocus/frame_report.h>
#include <defocus/frame_scheduler.h>
#include <defocus/io/frames.h>
#include <defocus/io/image_output.h>
#include <defocus/run_shot.h>
#include <defocus/io/shot_file.h>
#include <defocus/version.h>

#include "cli_options.h"
#include "defocus_help.h"
#include "process_memory.h"
#include "progress.h"

using namespace OIIO;
using namespace defocus;
using Strutil::fmt::format;

namespace {

struct CommandLine {
    Shot shot;
    std::string output, preview, display, display_view, save_scene, chunk;
    std::string scene_file;  ///< the .dof read, if any
    bool verbose = false, quiet = false, stop_on_error = false, preview_alpha = false;
    bool skip_existing = false;
    int threads = 0;
    int chunk_k = 0, chunk_n = 0;  ///< --chunk K/N; 0: all frames
};

/// The command's options, in --help order: the shot's (into `shot_args`)
/// among the command's own (into `cl`); the inputs into `inputs`.
void add_options(ArgParse& ap, CommandLine& cl, ShotArguments& shot_args,
                 std::vector<std::string>& inputs)
{
    ap.arg("filename").hidden().action([&](cspan<const char*> argv) {
        inputs.emplace_back(argv[0]);
    });

    shot_args.add_options(ap, OptionGroup::Sequences);
    ap.arg("--stop-on-error").help("Stop at the first bad frame (default: report it, "
                                   "write the others, exit non-zero)")
        .action([&](cspan<const char*>) { cl.stop_on_error = true; });
    ap.arg("--chunk K/N")
        .help("Render only the K-th of N chunks of the frames: neighbouring frames, every "
              "frame in exactly one chunk (for render farms; see defocus-submit)")
        .action(shot_args.store_into(cl.chunk));
    ap.arg("--skip-existing")
        .help("Skip frames whose output was written with the same settings by this version "
              "of defocus (the output records them: defocus:settingsHash) and is whole; "
              "render the others, -v says why")
        .action([&](cspan<const char*>) { cl.skip_existing = true; });
    shot_args.add_options(ap, OptionGroup::Camera);
    shot_args.add_options(ap, OptionGroup::Aperture);
    shot_args.add_options(ap, OptionGroup::Scene);
    ap.separator("Colour (OpenColorIO; spreading happens in scene-linear light):");
    shot_args.add_options(ap, OptionGroup::InputColor);
    shot_args.add_options(ap, OptionGroup::OutputColor);
    ap.arg("--preview FILE")
        .help("Also write an 8-bit display-referred preview (e.g. a .png) of the display "
              "window; a frame pattern for sequences")
        .action(shot_args.store_into(cl.preview));
    ap.arg("--preview-alpha")
        .help("Keep alpha in the preview (default: the preview is composited over black, "
              "so what shows through is not up to the viewer)")
        .action([&](cspan<const char*>) { cl.preview_alpha = true; });
    ap.arg("--display NAME")
        .help("Display for --preview (default: the config's default display)")
        .action(shot_args.store_into(cl.display));
    ap.arg("--display-view NAME")
        .help("View of that display for --preview (default: the display's default view; "
              "--view is the EXR view of the input)")
        .action(shot_args.store_into(cl.display_view));
    ap.separator("Output:");
    ap.arg("-o FILE")
        .help("Output file, or frame pattern for sequences (required); its extension "
              "picks the format")
        .action(shot_args.store_into(cl.output));
    shot_args.add_options(ap, OptionGroup::Output);
    ap.arg("--save-scene FILE")
        .help("Write the inputs and settings as a .dof scene file (without -o: only that)")
        .action(shot_args.store_into(cl.save_scene));
    ap.separator("General:");
    ap.arg("-v").help("Verbose: settings, layers, pixel fixes and per-stage timings")
        .action([&](cspan<const char*>) { cl.verbose = true; });
    ap.arg("-q").help("Quiet: no progress, only errors")
        .action([&](cspan<const char*>) { cl.quiet = true; });
    shot_args.add_threads(ap);
    add_version_option(ap, "defocus");
}

/// Reads the arguments into `cl`. False with `error` the problem; true
/// with `help_only` set when --help printed the help.
bool parse_command_line(int argc, const char* argv[], CommandLine& cl, bool& help_only,
                        std::string& error)
{
    auto fail = [&](std::string why) {
        error = std::move(why);
        return false;
    };
    ArgParse ap;
    describe_defocus(ap);
    std::vector<std::string> inputs;
    ShotArguments shot_args;
    add_options(ap, cl, shot_args, inputs);
    if (parse_arguments(ap, argc, argv) < 0)
        return fail(unknown_option_hint(ap, ap.geterror()));
    if (ap.aborted()) {  // --help
        help_only = true;
        return true;
    }

    const bool from_file = inputs.size() == 1 && Strutil::iends_with(inputs[0], ".dof");
    if (from_file) {
        cl.scene_file = inputs[0];
        if (!load_shot(inputs[0], cl.shot, error))
            return false;
    } else {
        for (const std::string& input : inputs)
            if (Strutil::iends_with(input, ".dof"))
                return fail(input + ": a .dof scene file must be the only input");
        cl.shot.inputs = inputs;
    }
    if (!shot_args.apply(cl.shot, error) || !shot_args.threads(cl.threads, error)
        || (!cl.chunk.empty() && !parse_chunk("--chunk", cl.chunk, cl.chunk_k, cl.chunk_n, error)))
        return false;
    if (inputs.empty())
        return fail("no input file (usage: defocus INPUT -o OUTPUT [options]; see --help)");
    if (!check_shot(cl.shot, error))
        return false;
    if (cl.shot.output != OutputKind::Image && !cl.preview.empty())
        return fail(format("--preview does not apply to --output {}, which is already a "
                           "display image",
                           output_kind_name(cl.shot.output)));
    if (cl.output.empty() && cl.save_scene.empty())
        return fail("no output file: give -o OUTPUT");
    return true;
}

bool write_preview(const FrameResult& frame, const CommandLine& cl, const std::string& file,
                   std::string& error)
{
    ImageBuf preview;
    if (!preview_image(frame, cl.display, cl.display_view, cl.preview_alpha, preview, error)) {
        error = (frame.color.config ? "--preview: " : "--preview needs an OpenColorIO config: ")
                + error;
        return false;
    }
    return write_image_atomic(preview, file, TypeUInt8, "", error);
}

/// The run the command line asks for: -o and --preview through the frames,
/// the .dof read and the one saved kept apart from every output.
RunRequest run_request(const CommandLine& cl)
{
    RunRequest request;
    request.output = cl.output;
    request.output_option = "-o";
    request.chunk = cl.chunk_k;
    request.chunks = cl.chunk_n;
    request.skip_existing = cl.skip_existing;
    request.sides.push_back({ "--preview", cl.preview, "",
                              [&cl](const FrameResult& frame, const std::string& file,
                                    std::string& error) {
                                  return write_preview(frame, cl, file, error);
                              } });
    request.also_read = { cl.scene_file };
    request.also_written = { cl.save_scene };
    request.threads = cl.threads;
    request.stop_on_error = cl.stop_on_error;
    return request;
}

/// -v says which frames --skip-existing leaves, and why a frame that exists
/// is rendered again.
void report_existing(const CommandLine& cl, const RunPlan& plan)
{
    if (!cl.verbose)
        return;
    auto label = [&](int frame) {
        return is_sequence(cl.shot) ? format("frame {}: ", frame) : std::string();
    };
    for (const RunPlan::Existing& e : plan.skipped)
        Strutil::print("defocus {}skipped: {} is written with these settings\n", label(e.frame),
                       e.output);
    for (const RunPlan::Existing& e : plan.again)
        Strutil::print("defocus {}rendering again: {} {}\n", label(e.frame), e.output, e.why);
}

/// A farm task's log begins with where, when and what it ran.
void print_farm_header(const CommandLine& cl, const std::vector<int>& frames)
{
    char host[256] = {};
    ::gethostname(host, sizeof host - 1);
    const std::time_t now = std::time(nullptr);
    char date[32];
    std::strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S UTC", std::gmtime(&now));
    Strutil::print("defocus {} on {} at {}: chunk {}, frames {}\n", version(), host, date,
                   cl.chunk, frame_ranges(frames));
    std::fflush(stdout);
}

/// Renders the planned frames, reporting as they go; the exit status.
int render(const CommandLine& cl, const ShotAssets& assets, const RunRequest& request,
           const RunPlan& plan)
{
    const Shot& shot = cl.shot;
    OIIO::attribute("threads", cl.threads);
    const bool sequence = is_sequence(shot);
    const ProgressMode mode = cl.quiet ? ProgressMode::Quiet
                              : isatty(STDOUT_FILENO) ? ProgressMode::Bar
                                                      : ProgressMode::Lines;
    Progress progress(mode, int(plan.frames.size()));
    // Display-referred output from a guessed input space may be wrong.
    const bool display_referred = !cl.preview.empty() || !shot.output_space.empty();
    const RunCallbacks callbacks = progress.run_callbacks(shot, cl.verbose, display_referred);
    const ScheduleResult run = run_plan(shot, assets, plan, request, callbacks);
    progress.finish();
    if (sequence) {
        const std::string summary = frames_written(run, plan.frames, int(plan.skipped.size()));
        if (!run.failed.empty())
            Strutil::print(stderr, "defocus: {}\n",
                           error_line(summary, SettingForm::CommandLine));
        else if (!cl.quiet)
            Strutil::print("defocus: {}\n", summary);
    } else if (!plan.skipped.empty() && !cl.quiet) {
        Strutil::print("defocus: {} is written with these settings: skipped\n", cl.output);
    }
    return run.failed.empty() ? EXIT_SUCCESS : EXIT_FAILURE;
}

}  // namespace

int main(int argc, const char* argv[])
{
    remove_temporaries_on_interrupt("defocus");
    Filesystem::convert_native_arguments(argc, argv);
    CommandLine cl;
    bool help_only = false;
    std::string error;
    const bool parsed = parse_command_line(argc, argv, cl, help_only, error);
    if (help_only)
        return EXIT_SUCCESS;
    auto fail = [](const std::string& message) {
        Strutil::print(stderr, "defocus: {}\n",
                       error_line(message, SettingForm::CommandLine));
        return EXIT_FAILURE;
    };
    if (!parsed)
        return fail(error);
    const Shot& shot = cl.shot;
    if (!shot.deep)
        keep_freed_memory();
    // Read once, for every frame.
    ShotAssets assets;
    if (!read_shot_assets(shot, assets, error))
        return fail(error);
    // The limit bounds the process, not only its frames: what it holds
    // before the first frame (its code and libraries, 120 MB) is counted,
    // and what comes and goes beside the frames' images: worker threads'
    // stacks, the file encoders' buffers (up to 25 MB at 4K).
    const double transient = 32.0 * 1024 * 1024;
    const double process = resident_bytes() + transient;
    cl.shot.read.memory_limit = shot.read.memory_limit.beside_process(process);
    cl.shot.layering.memory_limit = shot.layering.memory_limit.beside_process(process);
    const RunRequest request = run_request(cl);
    RunPlan plan;
    if (!plan_run(shot, request, plan, error))
        return fail(error);
    report_existing(cl, plan);
    if (plan.frames.empty() && plan.skipped.empty()) {
        if (!cl.quiet)
            Strutil::print("defocus: chunk {} has no frames ({} frames in {} chunks)\n", cl.chunk,
                           plan.shot_frame_count, cl.chunk_n);
        return EXIT_SUCCESS;
    }
    if (!plan.missing.empty() && !cl.quiet)
        Strutil::print(stderr, "defocus: warning: frames with input files missing {}: {}\n",
                       shot.missing_frames == MissingFrames::Skip
                           ? "are not rendered (--missing-frames skip)"
                           : "are rendered from the nearest earlier frame's (--missing-frames "
                             "hold)",
                       frame_ranges(plan.missing));
    if (!cl.save_scene.empty()) {
        if (!save_shot(shot, cl.save_scene, error))
            return fail(error);
        if (!cl.quiet)
            Strutil::print("wrote {}\n", cl.save_scene);
        if (cl.output.empty())
            return EXIT_SUCCESS;
    }
    if (cl.chunk_n > 0 && !cl.quiet)
        print_farm_header(cl, plan.frames);
    return render(cl, assets, request, plan);
}
