#include "progress.h"

#include <algorithm>
#include <cstdio>

#include <OpenImageIO/strutil.h>

#include <defocus/error_line.h>
#include <defocus/frame_report.h>
#include <defocus/io/frames.h>

#include "cli_options.h"

namespace defocus {

using OIIO::Strutil::fmt::format;

namespace {

/// The width of a progress line: the terminal's, less the column a
/// terminal wraps at.
size_t line_width()
{
    const int columns = terminal_columns();
    return size_t(columns >= 40 ? columns - 1 : 79);
}

}  // namespace

Progress::Progress(ProgressMode mode, int frames)
    : m_mode(mode)
    , m_frames(frames)
{
}

void Progress::stage(const std::string& frame, const char* stage)
{
    if (m_mode != ProgressMode::Bar)
        return;
    std::lock_guard<std::mutex> lock(m_mutex);
    m_current = frame.empty() ? std::string(stage) : frame + ": " + stage;
    draw_bar();
}

void Progress::written(const std::string& frame, const std::string& file, double seconds)
{
    std::lock_guard<std::mutex> lock(m_mutex);
    ++m_written;
    m_last_written = file;
    if (m_mode != ProgressMode::Lines)
        return;
    const std::string done = m_frames > 1 ? format(" ({}/{})", m_over + 1, m_frames) : "";
    OIIO::Strutil::print("{}{}{}wrote {} in {:.2f} s\n", frame, done,
                         frame.empty() ? "" : ": ", file, seconds);
    std::fflush(stdout);
}

void Progress::text(const std::string& text)
{
    if (m_mode == ProgressMode::Quiet)
        return;
    std::lock_guard<std::mutex> lock(m_mutex);
    clear_bar();
    OIIO::Strutil::print("{}", in_words(text, SettingForm::CommandLine));
    std::fflush(stdout);
    draw_bar();
}

void Progress::error(const std::string& message)
{
    std::lock_guard<std::mutex> lock(m_mutex);
    clear_bar();
    OIIO::Strutil::print(stderr, "defocus: {}\n",
                         error_line(message, SettingForm::CommandLine));
    std::fflush(stderr);
    draw_bar();
}

void Progress::frame_over()
{
    std::lock_guard<std::mutex> lock(m_mutex);
    ++m_over;
    draw_bar();
}

void Progress::finish()
{
    std::lock_guard<std::mutex> lock(m_mutex);
    clear_bar();
    m_current.clear();
    // The bar leaves nothing behind, so its last word is a line that stays.
    if (m_mode != ProgressMode::Bar || m_written == 0)
        return;
    if (m_frames == 1)
        OIIO::Strutil::print("wrote {} in {:.2f} s\n", m_last_written, m_timer());
    else
        OIIO::Strutil::print("wrote {} of {} frames in {:.2f} s\n", m_written, m_frames,
                             m_timer());
    std::fflush(stdout);
}

void Progress::clear_bar()
{
    if (!m_bar_drawn)
        return;
    OIIO::Strutil::print("\r{:{}}\r", "", line_width());
    m_bar_drawn = false;
}

void Progress::draw_bar()
{
    if (m_mode != ProgressMode::Bar || m_current.empty())
        return;
    const int width   = 24;
    const int filled  = m_frames > 0 ? width * m_over / m_frames : 0;
    const double time = m_timer();
    std::string eta   = "--:--";
    if (m_over > 0) {
        const int left = int(time / m_over * (m_frames - m_over) + 0.5);
        eta = format("{}:{:02}", left / 60, left % 60);
    }
    std::string line = format("[{}{}] {}/{}  {}  ETA {}", std::string(filled, '#'),
                              std::string(width - filled, '.'), m_over, m_frames,
                              m_current, eta);
    const size_t columns = line_width();
    if (line.size() > columns)
        line.resize(columns);
    OIIO::Strutil::print("\r{:<{}}", line, columns);
    std::fflush(stdout);
    m_bar_drawn = true;
}

RunCallbacks Progress::run_callbacks(const Shot& shot, bool verbose, bool display_referred)
{
    const bool sequence = is_sequence(shot);
    auto label = [sequence](int frame) { return sequence ? format("frame {}", frame) : ""; };
    RunCallbacks callbacks;
    callbacks.stage = [this, label](int frame, const char* name) {
        if (name)
            stage(label(frame), name);
        return true;
    };
    callbacks.written = [=, &shot](int frame, const std::string& output,
                                   const FrameResult& result, double seconds) {
        if (display_referred && !result.color.guess.empty())
            std::call_once(m_guess_warning, [&] {
                error(format("warning: {}: input colour space '{}' is a guess ({}); give "
                             "--iscolorspace to be sure",
                             result.source, result.color.input, result.color.guess));
            });
        if (verbose)
            text(format("defocus {}{}{} -> {}\n", label(frame), sequence ? ": " : "",
                        result.source, output)
                 + frame_report(result, shot, output));
        written(label(frame), output, seconds);
        frame_over();
    };
    callbacks.failed = [this, label, sequence](int frame, const std::string& message) {
        error(sequence ? label(frame) + ": " + message : message);
        frame_over();
    };
    return callbacks;
}

}  // namespace defocus
