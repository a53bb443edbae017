// The command-line options that set a shot's settings, with their help.
// The tools register them from here, a group at a time, so that a new
// setting reaches every tool that offers its group.
#pragma once

#include <vector>

namespace defocus {

/// Where an option shows in a tool's --help.
enum class OptionGroup {
    Sequences,    ///< which frames
    Camera,       ///< focus, lens and filmback
    Aperture,     ///< the bokeh's shape and how it is spread
    Scene,        ///< what in the input is read, and how it is cut into layers
    InputColor,   ///< the input's colour space
    OutputColor,  ///< the output's colour space
    Output,       ///< what is written
};

struct ShotOption {
    OptionGroup group;
    const char* spec;     ///< as ArgParse takes it: "--focus DIST", or a switch: "--crop"
    const char* setting;  ///< the shot setting it sets (see shot_settings())
    const char* help;
    const char* value = nullptr;  ///< what a switch sets the setting to
};

/// Every option, in --help order.
const std::vector<ShotOption>& shot_options();

/// The heading a tool prints above a group's options, "" for the groups
/// whose heading the tool words itself (it shares it with its own options).
const char* option_group_heading(OptionGroup group);

}  // namespace defocus
