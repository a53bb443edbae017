// What the defocus command tells the user while it works: a progress bar
// on a terminal, plain lines when stdout is not one, nothing when quiet.
// Errors always go to stderr. Safe to call from several frame workers.
#pragma once

#include <mutex>
#include <string>

#include <OpenImageIO/timer.h>

#include <defocus/run_shot.h>

namespace defocus {

enum class ProgressMode {
    Bar,    ///< one redrawn line: frames done, the current stage, the ETA
    Lines,  ///< a line per frame written
    Quiet,  ///< errors only
};

class Progress {
public:
    Progress(ProgressMode mode, int frames);

    /// A frame worker started `stage` ("read", "render", ...) of `frame`.
    void stage(const std::string& frame, const char* stage);
    /// A frame was written (one line in Lines mode; in Bar mode the
    /// count, which finish() reports).
    void written(const std::string& frame, const std::string& file, double seconds);
    /// A block of text for stdout (the -v report), whole.
    void text(const std::string& text);
    /// A one-line error or warning, on stderr.
    void error(const std::string& message);
    /// A frame is over, written or not.
    void frame_over();
    /// Clears the bar, and in Bar mode says in one line what was written.
    void finish();

    /// Callbacks that report a run of `shot` here: each stage, each frame
    /// written (with -v, its report) or failed, and, once a run, a warning
    /// when the input colour space was guessed and the output is
    /// `display_referred`.
    RunCallbacks run_callbacks(const Shot& shot, bool verbose, bool display_referred);

private:
    void clear_bar();
    void draw_bar();

    std::mutex m_mutex;
    ProgressMode m_mode;
    int m_frames, m_over = 0, m_written = 0;
    std::string m_last_written;
    std::string m_current;  ///< "frame 1004: render"
    OIIO::Timer m_timer;
    bool m_bar_drawn = false;
    std::once_flag m_guess_warning;
};

}  // namespace defocus
