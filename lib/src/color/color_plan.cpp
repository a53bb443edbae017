#include <defocus/color/color_plan.h>

#include <OpenImageIO/strutil.h>

#include <defocus/color/primaries.h>
#include <defocus/shot/setting_words.h>

namespace defocus {

using OIIO::Strutil::fmt::format;

namespace {

/// The space an input file names precisely, and by which rule (its
/// colorInteropID, a specific oiio:ColorSpace tag, or the chromaticities
/// of a linear float image); "" when it names none the config has.
std::string named_space(const ColorManagement& c, const OIIO::ImageSpec& spec, std::string& rule)
{
    const std::string id = spec.get_string_attribute("colorInteropID");
    const KnownSpace* by_id = space_with_interop_id(id);
    if (by_id && !config_space(c, *by_id).empty()) {
        rule = format("the file's colorInteropID '{}'", id);
        return config_space(c, *by_id);
    }
    const std::string tag = spec.get_string_attribute("oiio:ColorSpace");
    if (!OIIO::Strutil::iequals(tag, "linear") && !c.find_space(tag).empty()) {
        rule = format("the file's colour space tag '{}'", tag);
        return c.find_space(tag);
    }
    const OIIO::ParamValue* xy = spec.find_attribute("chromaticities",
                                                     OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 8));
    const KnownSpace* by_xy = xy && spec.format.is_floating_point()
                                  ? linear_space_with_chromaticities(
                                        static_cast<const float*>(xy->data()))
                                  : nullptr;
    if (by_xy && !config_space(c, *by_xy).empty()) {
        rule = format("the file's chromaticities: {}", by_xy->description);
        return config_space(c, *by_xy);
    }
    return "";
}

}  // namespace

bool plan_color(ColorPlan& plan, std::shared_ptr<const ColorManagement> config,
                const std::string& no_config, const std::string& input_space,
                const std::string& output_space, const OIIO::ImageSpec& input_spec,
                std::string& error)
{
    plan.config = std::move(config);
    if (!plan.config) {
        if (!input_space.empty() || !output_space.empty()) {
            error = no_config;
            return false;
        }
        plan.summary = "colour: no config (" + no_config + "); the input is taken as linear";
        return true;
    }
    const ColorManagement& c = *plan.config;
    const std::string tag = input_spec.get_string_attribute("oiio:ColorSpace");
    if (!input_space.empty()) {
        plan.input = c.require_space(input_space, error);
        if (plan.input.empty()) {
            error = mention("iscolorspace") + ": " + error;
            return false;
        }
    } else {
        plan.input = named_space(c, input_spec, plan.rule);
        if (plan.input.empty() && OIIO::Strutil::iequals(tag, "linear")) {
            // OIIO tags every EXR "Linear", whatever its primaries; most
            // such renders (Blender's, most renderers' defaults) are linear
            // Rec.709.
            plan.input = c.find_space("lin_rec709");
            plan.guess = format("the file's generic '{}' tag taken as linear Rec.709", tag);
        } else if (plan.input.empty() && tag.empty() && !input_spec.format.is_floating_point()) {
            // 8- and 16-bit images are display-referred, as OpenImageIO
            // takes them.
            plan.input = c.find_space("srgb_tx");
            plan.guess = format("an untagged {}-bit image taken as sRGB, as OpenImageIO does",
                                input_spec.format.size() * 8);
        }
    }
    if (!plan.input.empty() && c.is_data(plan.input)) {
        error = format("{}: '{}' is data, not colour: the input must be in a colour space",
                       mention("iscolorspace"), plan.input);
        return false;
    }
    if (plan.input.empty()) {
        plan.input = c.scene_linear();  // linear, as far as anyone can tell
        plan.guess = tag.empty() ? "no colour space tag: taken as the config's scene_linear"
                                 : format("tag '{}' unknown to the config: taken as its "
                                          "scene_linear", tag);
    }
    plan.output = plan.input;
    if (!output_space.empty()) {
        plan.output = c.require_space(output_space, error);
        if (plan.output.empty()) {
            error = mention("tocolorspace") + ": " + error;
            return false;
        }
    }
    // Spreading commutes with the 3x3 matrix between two linear spaces, so
    // a linear input is spread as it is.
    plan.convert_input = !c.is_linear(plan.input);
    plan.working       = plan.convert_input ? c.scene_linear() : plan.input;
    plan.summary = format("colour: config {} ({}); input '{}'{}, spread in '{}', output '{}'",
                          c.path(), c.origin(), plan.input,
                          !plan.guess.empty()  ? " (a guess: " + plan.guess + ")"
                          : !plan.rule.empty() ? " (from " + plan.rule + ")"
                                               : std::string(),
                          plan.working, plan.output);
    return true;
}

}  // namespace defocus
