// A shot rendered to files, the sequence every front end runs: choose the
// frames, check every output against every input before any work, run the
// frames side by side within the memory limit, render each, write it
// atomically and report it. The defocus command and the Python module
// adapt it; the plugin renders single frames (render_frame.h).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <defocus/frame_scheduler.h>
#include <defocus/io/shot_assets.h>
#include <defocus/render_frame.h>
#include <defocus/shot/shot.h>

namespace defocus {

/// Files written beside each frame's image from its result (the CLI's
/// --preview), before the image itself.
struct SideOutput {
    std::string option;       ///< names it in errors ("--preview")
    std::string pattern;      ///< a frame pattern, as the output's; "" writes none
    std::string compression;  ///< checked as check_output() does ("" for the default)
    std::function<bool(const FrameResult& result, const std::string& file, std::string& error)>
        write;
};

/// What a run renders and where.
struct RunRequest {
    std::string output;                    ///< the images' frame pattern
    std::string output_option = "output";  ///< names it in errors ("-o" in the CLI)
    std::vector<int> frames;               ///< the frames to render; empty: the shot's
    int chunk = 0, chunks = 0;             ///< only the chunk-th of `chunks` (0: all)
    bool skip_existing = false;  ///< leave out frames whose output has these settings
    std::vector<SideOutput> sides;
    /// The front end's own files: read (a .dof scene file) and written (a
    /// scene saved), so that no output overwrites an input either.
    std::vector<std::string> also_read, also_written;
    int threads = 0;
    bool stop_on_error = false;
};

/// The frames a request renders, in order, and the files each writes.
struct RunPlan {
    std::vector<int> frames;
    std::vector<std::string> outputs;                  ///< per frame
    std::vector<std::vector<std::string>> side_files;  ///< per side output, per frame
    /// Frames whose input files are missing, which the shot skips or holds.
    std::vector<int> missing;
    size_t shot_frame_count = 0;  ///< before the chunk and skip_existing
    struct Existing {
        int frame;
        std::string output, why;  ///< why is "" where the output has these settings
    };
    /// With skip_existing: outputs found written with these settings (left
    /// out), and those rendered again though they exist, with why.
    std::vector<Existing> skipped, again;
};

/// Plans a run: its frames, and every output checked (writable, a format
/// for it) and checked against every file the run reads (no input, depth,
/// mask, PSF image, config or scene file is overwritten). False with
/// `error` a one-line message naming the file and the problem.
bool plan_run(const Shot& shot, const RunRequest& request, RunPlan& plan, std::string& error);

/// What a run reports as it goes, from the threads that render. A frame is
/// either written or failed, never both.
struct RunCallbacks {
    /// A stage of a frame starts ("read", "colour", "slice", "render",
    /// "write"), or with nullptr a long stage asks whether to go on; false
    /// cancels the run: that frame stops and no other starts, and neither
    /// is reported.
    std::function<bool(int frame, const char* stage)> stage;
    /// A frame is written; its result holds the stages' timings, "write"
    /// the last.
    std::function<void(int frame, const std::string& output, const FrameResult& result,
                       double seconds)>
        written;
    std::function<void(int frame, const std::string& error)> failed;
};

/// Renders and writes the planned frames with the shot's assets (read
/// once: read_shot_assets). Returns which frames failed or did not run;
/// `cancelled` tells whether a stage callback stopped the run.
ScheduleResult run_plan(const Shot& shot, const ShotAssets& assets, const RunPlan& plan,
                        const RunRequest& request, const RunCallbacks& callbacks,
                        bool* cancelled = nullptr);

}  // namespace defocus
