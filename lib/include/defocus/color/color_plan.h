// Which colour spaces a render works in: the input's, the working space
// the layers are spread in, and the output's.
#pragma once

#include <memory>
#include <string>

#include <OpenImageIO/imageio.h>

#include <defocus/color/color.h>

namespace defocus {

struct ColorPlan {
    std::shared_ptr<const ColorManagement> config;  ///< null: none, and none was needed
    std::string input, working, output;
    bool convert_input = false;  ///< the input is not linear: convert it to `working`
    /// Why the input space is a guess ("" when it was named or tagged
    /// precisely): display-referred output then may not be what was meant.
    std::string guess;
    /// What in the file named the input space ("" when the caller named
    /// it, or it is a guess).
    std::string rule;
    std::string summary;         ///< one line for -v
};

/// Plans the colour of a render of an input with `input_spec` in `config`.
/// `input_space` ("" = what the file names: its colorInteropID, else its
/// oiio:ColorSpace when the config knows it and it is not OIIO's generic
/// "Linear", else, for float pixels, the linear space of its
/// chromaticities; failing those, the guesses: "Linear" as lin_rec709,
/// untagged integers as sRGB, else scene_linear) and `output_space` ("" = the input's) must be spaces of the
/// config. Without a config (`no_config` says why) the input is taken as
/// linear, unless a space is named: then that is an error.
bool plan_color(ColorPlan& plan, std::shared_ptr<const ColorManagement> config,
                const std::string& no_config, const std::string& input_space,
                const std::string& output_space, const OIIO::ImageSpec& input_spec,
                std::string& error);

}  // namespace defocus
