#include <defocus/shot/shot.h>

#include <functional>
#include <type_traits>

#include <OpenImageIO/strutil.h>

#include <defocus/shot/option_value.h>

namespace defocus {

using OIIO::Strutil::fmt::format;

namespace {

using Setter = std::function<bool(Shot&, const std::string& label,
                                  const std::string& value, std::string& error)>;
using Getter = std::function<std::string(const Shot&)>;

struct SettingRule {
    ShotSetting setting;
    Setter set;
    Getter get;
};

/// A number setting; whole numbers for an int member.
template<typename Member>
SettingRule number(ShotSetting s, Member member, double lo, double hi)
{
    return { s,
             [=](Shot& shot, const std::string& label, const std::string& value,
                 std::string& error) {
                 auto& target = member(shot);
                 if constexpr (std::is_same_v<decltype(target), int&>)
                     return parse_whole_number(label, value, lo, hi, target, error);
                 else
                     return parse_number(label, value, lo, hi, target, error);
             },
             [=](const Shot& shot) { return format("{}", member(shot)); } };
}

template<typename Member>
SettingRule text(ShotSetting s, Member member)
{
    return { s,
             [=](Shot& shot, const std::string&, const std::string& value, std::string&) {
                 member(shot) = value;
                 return true;
             },
             [=](const Shot& shot) { return member(shot); } };
}

/// One of an enum's names, read and written by its own functions; `what`
/// and `choices` word the error.
template<typename Member, typename Enum>
SettingRule choice(ShotSetting s, Member member, bool (*parse)(const std::string&, Enum&),
                   const char* (*name)(Enum), const char* what, const char* choices)
{
    return { s,
             [=](Shot& shot, const std::string& label, const std::string& value,
                 std::string& error) {
                 if (parse(value, member(shot)))
                     return true;
                 error = format("{}: unknown {} '{}' (choose {})", label, what, value, choices);
                 return false;
             },
             [=](const Shot& shot) { return std::string(name(member(shot))); } };
}

/// Keyframes of `arity` numbers; setting them clears `other` (focus and
/// focus-at exclude each other).
SettingRule keyframes(ShotSetting s, Keyframes Shot::*member, int arity, double lo,
                      double hi, Keyframes Shot::*other = nullptr)
{
    return { s,
             [=](Shot& shot, const std::string& label, const std::string& value,
                 std::string& error) {
                 if (!Keyframes::parse(label, value, arity, lo, hi, shot.*member,
                                       error))
                     return false;
                 if (other)
                     shot.*other = Keyframes();
                 return true;
             },
             [=](const Shot& shot) { return (shot.*member).to_string(); } };
}

bool parse_switch(const std::string& text, bool& on)
{
    if (text != "on" && text != "off")
        return false;
    on = text == "on";
    return true;
}

const char* switch_name(bool on)
{
    return on ? "on" : "off";
}

using K = ShotValueKind;

/// What is read, and how it is cut into layers.
std::vector<SettingRule> scene_rules()
{
    return {
        text({ "frames", "scene", "frames", K::Text }, [](auto& s) -> auto& { return s.frames; }),
        choice({ "missing-frames", "scene", "missing_frames", K::Text },
               [](auto& s) -> auto& { return s.missing_frames; }, parse_missing_frames,
               missing_frames_name, "value", "error, skip or hold"),
        text({ "view", "scene", "view", K::Text }, [](auto& s) -> auto& { return s.read.view; }),
        text({ "layer", "scene", "layer", K::Text }, [](auto& s) -> auto& { return s.read.layer; }),
        number({ "layers", "scene", "layers", K::Number },
                     [](auto& s) -> auto& { return s.layering.layers; }, 0, 256),
        text({ "depth", "scene", "depth", K::FileOrName },
             [](auto& s) -> auto& { return s.read.depth; }),
        number({ "depth-scale", "scene", "depth_scale", K::Number },
               [](auto& s) -> auto& { return s.read.depth_scale; }, 1e-9, 1e9),
        // One limit, held by both stages that allocate what files ask for.
        { { "memory-limit", "scene", "memory_limit", K::Text },
          [](Shot& shot, const std::string& label, const std::string& value, std::string& error) {
              if (!MemoryLimit::parse(label, value, shot.read.memory_limit, error))
                  return false;
              shot.layering.memory_limit = shot.read.memory_limit;
              return true;
          },
          [](const Shot& shot) { return shot.read.memory_limit.to_string(); } },
    };
}

/// The camera: focus, lens and filmback, and the lens's effects.
std::vector<SettingRule> camera_rules()
{
    return {
        keyframes({ "focus", "camera", "focus", K::Keyframes }, &Shot::focus, 1, 1e-6,
                  1e30, &Shot::focus_at),
        keyframes({ "focus-at", "camera", "focus_at", K::Point }, &Shot::focus_at, 2,
                  -1e7, 1e7, &Shot::focus),
        number({ "focus-at-radius", "camera", "focus_at_radius", K::Number },
               [](auto& s) -> auto& { return s.focus_at_radius; }, 0, 50),
        keyframes({ "focus-tilt", "camera", "focus_tilt", K::Point }, &Shot::focus_tilt, 2,
                  -80, 80),
        keyframes({ "optical-centre", "camera", "optical_centre", K::Point },
                  &Shot::optical_centre, 2, -1e7, 1e7),
        { { "split-diopter", "camera", "split_diopter", K::Text },
          [](Shot& shot, const std::string& label, const std::string& value, std::string& error) {
              // X0,Y0,X1,Y1:DIST, DIST a number or keyframes F:D,F:D...
              const size_t colon = value.find(':');
              const std::vector<std::string> line =
                  OIIO::Strutil::splits(value.substr(0, colon), ",");
              Shot::SplitDiopterSetting split;
              if (colon == std::string::npos || line.size() != 4) {
                  error = label + ": expected X0,Y0,X1,Y1:DIST, got '" + value + "'";
                  return false;
              }
              for (int i = 0; i < 4; ++i)
                  if (!parse_number(label, line[i], -1e7, 1e7, split.line[i], error))
                      return false;
              if (!Keyframes::parse(label, value.substr(colon + 1), 1, 1e-6, 1e30, split.focus,
                                    error))
                  return false;
              shot.split_diopter = split;
              return true;
          },
          [](const Shot& shot) {
              const Shot::SplitDiopterSetting& s = shot.split_diopter;
              return s.focus.empty() ? std::string()
                                     : format("{},{},{},{}:{}", s.line[0], s.line[1], s.line[2],
                                              s.line[3], s.focus.to_string());
          } },
        keyframes({ "focal", "camera", "focal", K::Keyframes }, &Shot::focal_length_mm, 1,
                  1e-3, 1e5),
        keyframes({ "fstop", "camera", "fstop", K::Keyframes }, &Shot::fstop, 1, 0.1, 1e4),
        choice({ "camera-from-file", "camera", "from_file", K::Switch },
               [](auto& s) -> auto& { return s.camera_from_file; }, parse_switch, switch_name,
               "value", "on or off"),
        number({ "sensor", "camera", "sensor", K::Number },
               [](auto& s) -> auto& { return s.camera.sensor_width_mm; }, 1e-3, 1e4),
        choice({ "lens", "camera", "lens", K::Text },
               [](auto& s) -> auto& { return s.camera.lens; }, parse_lens_model,
               lens_model_name, "model", "thin or optical"),
        number({ "max-blur", "camera", "max_blur", K::Number },
               [](auto& s) -> auto& { return s.camera.max_blur_px; }, 0.0, 1e5),
        number({ "axial-ca", "camera", "axial_ca", K::Number },
               [](auto& s) -> auto& { return s.camera.axial_ca; }, -0.5, 0.5),
        number({ "lateral-ca", "camera", "lateral_ca", K::Number },
               [](auto& s) -> auto& { return s.camera.lateral_ca; }, -0.05, 0.05),
        number({ "cateye", "camera", "cateye", K::Number },
               [](auto& s) -> auto& { return s.camera.cateye; }, 0.0, 1.5),
    };
}

/// The bokeh's shape and how it is spread.
std::vector<SettingRule> aperture_rules()
{
    return {
        { { "aperture", "aperture", "shape", K::Text },
          [](Shot& shot, const std::string& label, const std::string& value, std::string& error) {
              Aperture& a = shot.spread.aperture;
              if (OIIO::Strutil::starts_with(value, "mask:")) {
                  a.shape     = ApertureShape::Mask;
                  a.mask_file = value.substr(5);
                  return true;
              }
              if (parse_aperture_shape(value, a.shape))
                  return true;
              error = label + ": unknown shape '" + value
                      + "' (choose disc, polygon, mask:FILE, box, tent or smooth)";
              return false;
          },
          [](const Shot& shot) {
              return std::string(aperture_shape_name(shot.spread.aperture.shape));
          } },
        text({ "aperture-mask", "aperture", "mask", K::Path },
             [](auto& s) -> auto& { return s.spread.aperture.mask_file; }),
        number({ "blades", "aperture", "blades", K::Number },
                     [](auto& s) -> auto& { return s.spread.aperture.blades; }, 3, 16),
        number({ "rotation", "aperture", "rotation", K::Number },
               [](auto& s) -> auto& { return s.spread.aperture.rotation_deg; }, -3600, 3600),
        number({ "roundness", "aperture", "roundness", K::Number },
               [](auto& s) -> auto& { return s.spread.aperture.roundness; }, 0, 1),
        number({ "aspect", "aperture", "aspect", K::Number },
               [](auto& s) -> auto& { return s.spread.aperture.aspect; }, 0.05, 20),
        { { "spread", "aperture", "spread", K::Text },
          [](Shot& shot, const std::string& label, const std::string& value, std::string& error) {
              if (value == "bounded" || value == "exact") {
                  shot.spread.exact_shape = value == "exact";
                  return true;
              }
              error = label + ": unknown method '" + value + "' (choose bounded or exact)";
              return false;
          },
          [](const Shot& shot) {
              return std::string(shot.spread.exact_shape ? "exact" : "bounded");
          } },
        text({ "psf-image", "aperture", "psf_image", K::Path },
             [](auto& s) -> auto& { return s.spread.psf_image; }),
        number({ "hybrid-threshold", "aperture", "hybrid_threshold", K::Number },
               [](auto& s) -> auto& { return s.spread.hybrid_threshold; }, 1.0, 1e6),
    };
}

/// Colour spaces.
std::vector<SettingRule> color_rules()
{
    return {
        text({ "colorconfig", "color", "config", K::Path },
             [](auto& s) -> auto& { return s.color_config; }),
        text({ "iscolorspace", "color", "input", K::Text },
             [](auto& s) -> auto& { return s.input_space; }),
        text({ "tocolorspace", "color", "output", K::Text },
             [](auto& s) -> auto& { return s.output_space; }),
    };
}

/// What is written, and how the frame's edges are treated.
std::vector<SettingRule> output_rules()
{
    return {
        { { "output", "output", "kind", K::Text },
          [](Shot& shot, const std::string& label, const std::string& value, std::string& error) {
              if (value == "image" || value == "focusmap") {
                  shot.output = value == "image" ? OutputKind::Image : OutputKind::FocusMap;
                  return true;
              }
              error = label + ": unknown kind '" + value + "' (choose image or focusmap)";
              return false;
          },
          [](const Shot& shot) {
              return std::string(shot.output == OutputKind::Image ? "image" : "focusmap");
          } },
        { { "pixel-type", "output", "type", K::Text },
          [](Shot& shot, const std::string& label, const std::string& value, std::string& error) {
              if (value == "half" || value == "float" || value.empty()) {
                  shot.pixel_type = OIIO::TypeDesc(value);
                  return true;
              }
              error = label + ": unknown type '" + value + "' (choose half or float)";
              return false;
          },
          [](const Shot& shot) {
              return shot.pixel_type == OIIO::TypeUnknown ? std::string()
                                                          : std::string(shot.pixel_type.c_str());
          } },
        text({ "compression", "output", "compression", K::Text },
             [](auto& s) -> auto& { return s.compression; }),
        choice({ "aov", "output", "aov", K::Text }, [](auto& s) -> auto& { return s.aov; },
               parse_aov, aov_name, "AOV", "none or confidence"),
        choice({ "window", "output", "window", K::Text },
               [](auto& s) -> auto& { return s.window; }, parse_output_window,
               output_window_name, "window", "input, display or grown"),
        choice({ "edge", "scene", "edge", K::Text }, [](auto& s) -> auto& { return s.edge; },
               parse_edge_mode, edge_mode_name, "edge", "auto, extend or black"),
    };
}

/// Every setting, in the order of a .dof's sections and of --help.
const std::vector<SettingRule>& rules()
{
    static const std::vector<SettingRule> table = [] {
        std::vector<SettingRule> all;
        for (auto section : { scene_rules, camera_rules, aperture_rules, color_rules,
                              output_rules }) {
            std::vector<SettingRule> rules = section();
            all.insert(all.end(), rules.begin(), rules.end());
        }
        return all;
    }();
    return table;
}

const SettingRule* find_rule(const std::string& name)
{
    for (const SettingRule& rule : rules())
        if (name == rule.setting.name)
            return &rule;
    return nullptr;
}

}  // namespace

const std::vector<ShotSetting>& shot_settings()
{
    static const std::vector<ShotSetting> settings = [] {
        std::vector<ShotSetting> list;
        for (const SettingRule& rule : rules())
            list.push_back(rule.setting);
        return list;
    }();
    return settings;
}

bool set_shot_setting(Shot& shot, const std::string& name, const std::string& value,
                      std::string& error, const std::string& label)
{
    const SettingRule* rule = find_rule(name);
    if (!rule) {
        error = format("unknown setting '{}'", name);
        return false;
    }
    const std::string where = label.empty() ? "--" + name : label;
    if (!rule->set(shot, where, value, error))
        return false;
    shot.given[name] = where;
    return true;
}

bool is_given(const Shot& shot, const std::string& name)
{
    const std::string value = shot_setting(shot, name);
    // Focus and focus-at clear each other: a cleared one is not given.
    return !value.empty() && (shot.given.count(name) || value != shot_setting(Shot(), name));
}

std::string setting_origin(const Shot& shot, const std::string& name)
{
    if (!is_given(shot, name))
        return "default";
    const auto at = shot.given.find(name);
    return at != shot.given.end() ? at->second : "set";
}

std::string shot_setting(const Shot& shot, const std::string& name)
{
    const SettingRule* rule = find_rule(name);
    return rule ? rule->get(shot) : std::string();
}

bool check_shot(const Shot& shot, std::string& error)
{
    auto fail = [&](std::string why) {
        error = std::move(why);
        return false;
    };
    if (shot.inputs.empty())
        return fail("no input file");
    if (shot.focus.empty() && shot.focus_at.empty() && !shot.camera_from_file)
        return fail("--focus DIST or --focus-at X,Y is required: where the focus is");
    const Aperture& aperture = shot.spread.aperture;
    if (aperture.shape == ApertureShape::Mask && aperture.mask_file.empty())
        return fail("--aperture mask:FILE needs the image of the shape");
    if (shot.output == OutputKind::FocusMap && shot.aov != Aov::None)
        return fail("--aov applies to the defocused image, not to --output focusmap");
    // Settings that shape only a polygon would do nothing to other apertures.
    if (aperture.shape != ApertureShape::Polygon)
        for (const char* polygon_only : { "blades", "roundness", "rotation" })
            if (is_given(shot, polygon_only)) {
                const auto label = shot.given.find(polygon_only);
                return fail(format("{} applies only to --aperture polygon (the aperture is {})",
                                   label != shot.given.end() ? label->second
                                                             : "--" + std::string(polygon_only),
                                   aperture_shape_name(aperture.shape)));
            }
    return true;
}

std::vector<std::string> shot_files(const Shot& shot)
{
    std::vector<std::string> files = shot.inputs;
    for (const std::string* file : { &shot.read.depth, &shot.spread.aperture.mask_file,
                                     &shot.spread.psf_image, &shot.color_config })
        if (!file->empty())
            files.push_back(*file);
    return files;
}

bool is_animated(const Shot& shot)
{
    return shot.focus.animated() || shot.focus_at.animated()
           || shot.focal_length_mm.animated() || shot.fstop.animated()
           || shot.focus_tilt.animated() || shot.split_diopter.focus.animated()
           || shot.optical_centre.animated();
}

Camera camera_at(const Shot& shot, int frame)
{
    Camera camera;
    static_cast<CameraBody&>(camera) = shot.camera;
    camera.focal_length_mm = shot.focal_length_mm.at(frame, Interpolation::Linear)[0];
    camera.fstop           = shot.fstop.at(frame, Interpolation::Reciprocal)[0];
    if (!shot.focus.empty())
        camera.focus_distance = shot.focus.at(frame, Interpolation::Reciprocal)[0];
    if (!shot.focus_tilt.empty()) {
        const Keyframes::Value tilt = shot.focus_tilt.at(frame, Interpolation::Linear);
        camera.tilt_deg[0] = tilt[0];
        camera.tilt_deg[1] = tilt[1];
    }
    if (!shot.optical_centre.empty()) {
        const Keyframes::Value centre = shot.optical_centre.at(frame, Interpolation::Linear);
        camera.axis_pixel = Imath::V2d(centre[0], centre[1]);
    }
    const Shot::SplitDiopterSetting& split = shot.split_diopter;
    if (!split.focus.empty())
        camera.split = { split.line[0], split.line[1], split.line[2], split.line[3],
                         split.focus.at(frame, Interpolation::Reciprocal)[0] };
    return camera;
}

}  // namespace defocus
