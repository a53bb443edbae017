#include <defocus/shot/shot.h>

#include <OpenImageIO/strutil.h>

#include <defocus/shot/setting_words.h>

#include "settings_table.h"
#include "util/parse_name.h"

namespace defocus {

using OIIO::Strutil::fmt::format;

namespace {

const SettingRule* find_rule(const std::string& name)
{
    for (const SettingRule& rule : setting_rules())
        if (name == rule.setting.name)
            return &rule;
    return nullptr;
}

}  // namespace

const std::vector<ShotSetting>& shot_settings()
{
    static const std::vector<ShotSetting> settings = [] {
        std::vector<ShotSetting> list;
        for (const SettingRule& rule : setting_rules())
            list.push_back(rule.setting);
        return list;
    }();
    return settings;
}

const ShotSetting* find_shot_setting(const std::string& name)
{
    const SettingRule* rule = find_rule(name);
    return rule ? &shot_settings()[size_t(rule - setting_rules().data())] : nullptr;
}

bool set_shot_setting(Shot& shot, const std::string& name, const std::string& value,
                      std::string& error, const std::string& label)
{
    const SettingRule* rule = find_rule(name);
    if (!rule) {
        error = format("unknown setting '{}'", name);
        return false;
    }
    const std::string where = label.empty() ? mention(name) : label;
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

std::string setting_label(const Shot& shot, const std::string& name)
{
    const auto label = shot.given.find(name);
    return label != shot.given.end() ? label->second : mention(name);
}

std::string shot_setting(const Shot& shot, const std::string& name)
{
    const SettingRule* rule = find_rule(name);
    return rule ? rule->get(shot) : std::string();
}

namespace {

/// Why a deep result cannot hold what `shot` asks for ("" when it can): a
/// deep sample has one alpha and no other channel than colour and depth.
std::string deep_refusal(const Shot& shot)
{
    const std::string deep = setting_label(shot, "deep");
    if (shot.output != OutputKind::Image)
        return format("{} writes the defocused image, not {}", deep,
                      mention("output", output_kind_name(shot.output)));
    if (shot.aov != Aov::None)
        return format("{} cannot be written with {}: a deep sample holds colour and depth only",
                      setting_label(shot, "aov"), deep);
    if (!shot.holdout.empty())
        return format("{} cannot be written with {}: merge the deep result with the holdout "
                      "instead",
                      setting_label(shot, "holdout"), deep);
    if (shot.data_channels != Shot().data_channels)
        return format("{} cannot be written with {}: a deep sample holds colour and depth only",
                      setting_label(shot, "data-channels"), deep);
    for (const char* name : { "axial-ca", "lateral-ca" })
        if (shot_setting(shot, name) != shot_setting(Shot(), name))
            return format("{} cannot be written with {}: each colour is occluded by its own "
                          "spread there, and a deep sample has one alpha",
                          setting_label(shot, name), deep);
    return "";
}

}  // namespace

bool parse_output_kind(const std::string& name, OutputKind& kind)
{
    return parse_name(name, { OutputKind::Image, OutputKind::FocusMap, OutputKind::Layers },
                      output_kind_name, kind);
}

const char* output_kind_name(OutputKind kind)
{
    return kind == OutputKind::FocusMap ? "focusmap" : kind == OutputKind::Layers ? "layers"
                                                                                  : "image";
}

bool check_shot(const Shot& shot, std::string& error)
{
    auto fail = [&](std::string why) {
        error = std::move(why);
        return false;
    };
    if (shot.inputs.empty())
        return fail("no input file");
    if (shot.depth_kind == DepthKind::Coc && !coc_map_conflict(shot).empty())
        return fail(coc_map_conflict(shot));
    if (shot.focus.empty() && shot.focus_at.empty() && !shot.camera_from_file
        && shot.depth_kind != DepthKind::Coc)
        return fail(format("{} or {} is required: where the focus is", mention("focus", "DIST"),
                           mention("focus-at", "X,Y")));
    const Aperture& aperture = shot.spread.aperture;
    if (aperture.shape == ApertureShape::Mask && aperture.mask_file.empty())
        return fail(mention("aperture", "mask:FILE") + " needs the image of the shape");
    if (shot.output != OutputKind::Image && shot.aov != Aov::None)
        return fail(format("{} applies to the defocused image, not to {}",
                           setting_label(shot, "aov"),
                           mention("output", output_kind_name(shot.output))));
    if (shot.deep && !deep_refusal(shot).empty())
        return fail(deep_refusal(shot));
    if (shot.output != OutputKind::Image && shot.data_channels != Shot().data_channels)
        return fail(format("{} applies to the defocused image, not {}",
                           setting_label(shot, "data-channels"),
                           mention("output", output_kind_name(shot.output))));
    // Settings that shape only a polygon would do nothing to other apertures.
    if (aperture.shape != ApertureShape::Polygon)
        for (const char* polygon_only : { "blades", "roundness", "rotation" })
            if (is_given(shot, polygon_only))
                return fail(format("{} applies only to {} (the aperture is {})",
                                   setting_label(shot, polygon_only),
                                   mention("aperture", "polygon"),
                                   aperture_shape_name(aperture.shape)));
    return true;
}

std::string coc_map_conflict(const Shot& shot)
{
    for (const char* name :
         { "focus", "focus-at", "focus-tilt", "split-diopter", "in-focus-range", "depth-scale" })
        if (is_given(shot, name))
            return format("{} has no meaning for a depth that is a CoC map ({}): the map "
                          "gives each pixel's blur",
                          setting_label(shot, name), mention("depth-kind", "coc"));
    return "";
}

std::vector<std::string> shot_files(const Shot& shot)
{
    std::vector<std::string> files = shot.inputs;
    for (const std::string* file : { &shot.read.depth, &shot.holdout,
                                     &shot.spread.aperture.mask_file, &shot.spread.psf_image,
                                     &shot.color_config })
        if (!file->empty())
            files.push_back(*file);
    return files;
}

bool is_animated(const Shot& shot)
{
    return shot.focus.animated() || shot.focus_at.animated()
           || shot.focal_length_mm.animated() || shot.fstop.animated()
           || shot.focus_tilt.animated() || shot.split_diopter.focus.animated()
           || shot.optical_centre.animated() || shot.bloom.animated();
}

Aov output_aov(const Shot& shot)
{
    return shot.output == OutputKind::Image ? shot.aov : Aov::None;
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
