#include <defocus/color_plan.h>

#include <OpenImageIO/strutil.h>

namespace defocus {

using OIIO::Strutil::fmt::format;

bool plan_color(ColorPlan& plan, const std::string& config_file,
                const std::string& input_space, const std::string& output_space,
                const OIIO::ImageSpec& input_spec, std::string& error)
{
    const bool asked = !config_file.empty() || !input_space.empty()
                       || !output_space.empty();
    std::string load_error;
    plan.loaded = plan.config.load(config_file, load_error);
    if (!plan.loaded) {
        if (asked) {
            error = load_error;
            return false;
        }
        plan.summary = "colour: no config (" + load_error + "); the input is taken as linear";
        return true;
    }
    const ColorManagement& c = plan.config;
    if (!input_space.empty()) {
        plan.input = c.require_space(input_space, error);
        if (plan.input.empty()) {
            error = "--iscolorspace: " + error;
            return false;
        }
    } else {
        plan.input = c.find_space(input_spec.get_string_attribute("oiio:ColorSpace"));
    }
    if (!plan.input.empty() && c.is_data(plan.input)) {
        error = format("--iscolorspace: '{}' is data, not colour: the input must be in "
                       "a colour space",
                       plan.input);
        return false;
    }
    if (plan.input.empty())
        plan.input = c.scene_linear();  // linear, as far as anyone can tell
    plan.output = plan.input;
    if (!output_space.empty()) {
        plan.output = c.require_space(output_space, error);
        if (plan.output.empty()) {
            error = "--tocolorspace: " + error;
            return false;
        }
    }
    // Spreading commutes with the 3x3 matrix between two linear spaces, so
    // a linear input is spread as it is.
    plan.convert_input = !c.is_linear(plan.input);
    plan.working       = plan.convert_input ? c.scene_linear() : plan.input;
    plan.summary = format("colour: config {} ({}); input '{}', spread in '{}', output '{}'",
                          c.path(), c.origin(), plan.input, plan.working, plan.output);
    return true;
}

}  // namespace defocus
