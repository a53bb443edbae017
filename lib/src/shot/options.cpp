#include <defocus/shot/options.h>

#include "util/parse_name.h"

namespace defocus {

bool parse_edge_mode(const std::string& name, EdgeMode& mode)
{
    return parse_name(name, { EdgeMode::Auto, EdgeMode::Extend, EdgeMode::Black },
                      edge_mode_name, mode);
}

const char* edge_mode_name(EdgeMode mode)
{
    switch (mode) {
    case EdgeMode::Auto: return "auto";
    case EdgeMode::Extend: return "extend";
    case EdgeMode::Black: return "black";
    }
    return "?";
}

bool parse_missing_frames(const std::string& name, MissingFrames& missing)
{
    return parse_name(name, { MissingFrames::Error, MissingFrames::Skip, MissingFrames::Hold },
                      missing_frames_name, missing);
}

const char* missing_frames_name(MissingFrames missing)
{
    switch (missing) {
    case MissingFrames::Error: return "error";
    case MissingFrames::Skip: return "skip";
    case MissingFrames::Hold: return "hold";
    }
    return "?";
}

bool parse_output_window(const std::string& name, OutputWindow& window)
{
    return parse_name(name, { OutputWindow::Input, OutputWindow::Display, OutputWindow::Grown },
                      output_window_name, window);
}

bool parse_aov(const std::string& name, Aov& aov)
{
    return parse_name(name, { Aov::None, Aov::Confidence, Aov::Coc }, aov_name, aov);
}

const char* aov_name(Aov aov)
{
    switch (aov) {
    case Aov::Confidence: return "confidence";
    case Aov::Coc: return "coc";
    default: return "none";
    }
}

const char* output_window_name(OutputWindow window)
{
    switch (window) {
    case OutputWindow::Input: return "input";
    case OutputWindow::Display: return "display";
    case OutputWindow::Grown: return "grown";
    }
    return "?";
}

}  // namespace defocus
