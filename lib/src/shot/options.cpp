#include <defocus/shot/options.h>

namespace defocus {

bool parse_edge_mode(const std::string& name, EdgeMode& mode)
{
    for (EdgeMode m : { EdgeMode::Auto, EdgeMode::Extend, EdgeMode::Black })
        if (name == edge_mode_name(m)) {
            mode = m;
            return true;
        }
    return false;
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

bool parse_output_window(const std::string& name, OutputWindow& window)
{
    for (OutputWindow w : { OutputWindow::Input, OutputWindow::Display, OutputWindow::Grown })
        if (name == output_window_name(w)) {
            window = w;
            return true;
        }
    return false;
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
