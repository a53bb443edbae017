#include "settings_table.h"

#include <type_traits>
#include <utility>

#include <OpenImageIO/strutil.h>

#include <defocus/shot/option_value.h>

namespace defocus {

using OIIO::Strutil::fmt::format;

namespace {

using K = ShotValueKind;
using G = OptionGroup;

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

/// One of two values, each written as its name: `first` or `second`.
template<typename Member, typename Value>
SettingRule either(ShotSetting s, Member member, const char* what,
                   std::pair<const char*, Value> first, std::pair<const char*, Value> second)
{
    return { s,
             [=](Shot& shot, const std::string& label, const std::string& value,
                 std::string& error) {
                 for (const auto& [name, meaning] : { first, second })
                     if (value == name) {
                         member(shot) = meaning;
                         return true;
                     }
                 error = format("{}: unknown {} '{}' (choose {} or {})", label, what, value,
                                first.first, second.first);
                 return false;
             },
             [=](const Shot& shot) {
                 return std::string(member(shot) == first.second ? first.first : second.first);
             } };
}

/// Keyframes of `arity` numbers; setting them clears `other` (focus and
/// focus-at exclude each other).
SettingRule keyframes(ShotSetting s, Keyframes Shot::*member, int arity, double lo,
                      double hi, Keyframes Shot::*other = nullptr)
{
    // The value as the option's help names it: "--bloom THRESHOLD,GAIN".
    const std::string option = s.option ? s.option : "";
    const std::string placeholder
        = option.find(' ') == std::string::npos ? "" : option.substr(option.find(' ') + 1);
    return { s,
             [=](Shot& shot, const std::string& label, const std::string& value,
                 std::string& error) {
                 if (!Keyframes::parse(label, value, arity, lo, hi, shot.*member, error,
                                       placeholder))
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

/// Which frames.
std::vector<SettingRule> sequence_rules()
{
    return {
        text({ "frames", "scene", "frames", K::Text, G::Sequences, "--frames LIST",
               "Frames to render: 1001-1100, 1-99x2 (every other), 1,5,9-12 "
               "(default: the frames the input pattern finds on disk)" },
             [](auto& s) -> auto& { return s.frames; }),
        choice({ "missing-frames", "scene", "missing_frames", K::Text, G::Sequences,
                 "--missing-frames error|skip|hold",
                 "Frames whose input files are missing (a gap in the sequence on disk, or a "
                 "frame of --frames): error refuses the shot, naming them; skip renders the "
                 "others; hold renders each from the nearest earlier frame's inputs "
                 "(default: error)" },
               [](auto& s) -> auto& { return s.missing_frames; }, parse_missing_frames,
               missing_frames_name, "value", "error, skip or hold"),
    };
}

/// What in the input is read, and how it is cut into layers.
std::vector<SettingRule> scene_rules()
{
    return {
        text({ "view", "scene", "view", K::Text, G::Scene, "--view NAME",
               "View of a multi-view EXR (default: the first part's view)" },
             [](auto& s) -> auto& { return s.read.view; }),
        text({ "layer", "scene", "layer", K::Text, G::Scene, "--layer NAME",
               "Channel prefix of colour and depth, e.g. 'beauty' for beauty.R..beauty.Z, or "
               "Blender's view layer name (default: plain R,G,B,A,Z or the file's only "
               "prefixed set)" },
             [](auto& s) -> auto& { return s.read.layer; }),
        number({ "layers", "scene", "layers", K::Number, G::Scene, "--layers N",
                 "Depth layers to cut deep and flat inputs into, spaced evenly in CoC "
                 "(default: 0 = automatic: boundaries in the gaps between objects, at most "
                 "24 px of CoC per layer)" },
               [](auto& s) -> auto& { return s.layering.layers; }, 0, 256),
        text({ "depth", "scene", "depth", K::FileOrName, G::Scene, "--depth FILE|CHANNEL",
               "Depth for a render without Z, or instead of its Z: a channel of the input by "
               "name, or a depth image (its Z or only channel; a frame pattern for "
               "sequences)" },
             [](auto& s) -> auto& { return s.read.depth; }),
        number({ "depth-scale", "scene", "depth_scale", K::Number, G::Scene, "--depth-scale S",
                 "Metres per depth unit of the input's Z, e.g. 0.01 for centimetres "
                 "(default: 1; --focus stays in metres)" },
               [](auto& s) -> auto& { return s.read.depth_scale; }, 1e-9, 1e9),
        choice({ "depth-kind", "scene", "depth_kind", K::Text, G::Scene, "--depth-kind KIND",
                 "What the depth holds: z, planar camera-space depth (default); inverse, 1/z "
                 "with 0 infinitely far (Nuke's renderers; ZDefocus's far = 0); distance, "
                 "along each pixel's ray from the camera; coc, the signed CoC diameter in "
                 "pixels, negative in front of the focus, as --aov coc writes it (then no "
                 "focus applies and the camera's settings are unused). Not given, a header's "
                 "defocus:depthKind says" },
               [](auto& s) -> auto& { return s.depth_kind; }, parse_depth_kind, depth_kind_name,
               "depth kind", "z, inverse, distance or coc"),
        text({ "holdout", "scene", "holdout", K::Path, G::Scene, "--holdout FILE",
               "Hold the shot out by the other elements in this deep EXR (or flat RGBA+Z "
               "render; a frame pattern for sequences): where they stand in front, the "
               "defocused result is cut, per output pixel, by their transmittance, so that "
               "it merges with them later; they are neither defocused nor written" },
             [](auto& s) -> auto& { return s.holdout; }),
        // One limit, held by both stages that allocate what files ask for.
        { { "memory-limit", "scene", "memory_limit", K::Text, G::Scene,
            "--memory-limit SIZE",
            "The most memory rendering may take, e.g. 12G or 512M: the defocus command "
            "counts its own code and libraries in it, so that it bounds its peak; Python "
            "and the plugin count the frames' images. A file whose "
            "header asks for more (a giant data window, a deep file with billions of "
            "samples) is refused before anything is allocated (default: half the "
            "machine's memory)" },
          [](Shot& shot, const std::string& label, const std::string& value, std::string& error) {
              if (!MemoryLimit::parse(label, value, shot.read.memory_limit, error))
                  return false;
              shot.layering.memory_limit = shot.read.memory_limit;
              return true;
          },
          [](const Shot& shot) { return shot.read.memory_limit.to_string(); } },
    };
}

/// X0,Y0,X1,Y1:DIST, DIST a number or keyframes F:D,F:D...
bool parse_split_diopter(Shot& shot, const std::string& label, const std::string& value,
                         std::string& error)
{
    const size_t colon = value.find(':');
    const std::vector<std::string> line = OIIO::Strutil::splits(value.substr(0, colon), ",");
    Shot::SplitDiopterSetting split;
    if (colon == std::string::npos || line.size() != 4) {
        error = label + ": expected X0,Y0,X1,Y1:DIST, got '" + value + "'";
        return false;
    }
    for (int i = 0; i < 4; ++i)
        if (!parse_number(label, line[i], -1e7, 1e7, split.line[i], error))
            return false;
    if (!Keyframes::parse(label, value.substr(colon + 1), 1, 1e-6, 1e30, split.focus, error))
        return false;
    shot.split_diopter = split;
    return true;
}

std::string print_split_diopter(const Shot& shot)
{
    const Shot::SplitDiopterSetting& s = shot.split_diopter;
    return s.focus.empty() ? std::string()
                           : format("{},{},{},{}:{}", s.line[0], s.line[1], s.line[2],
                                    s.line[3], s.focus.to_string());
}

/// Where the lens focuses.
std::vector<SettingRule> focus_rules()
{
    return {
        keyframes({ "focus", "camera", "focus", K::Keyframes, G::Camera, "--focus DIST",
                    "Focus distance in metres, e.g. 3 or 1001:3,1040:1.2 (required, or "
                    "--focus-at, unless the render's header records it)" },
                  &Shot::focus, 1, 1e-6, 1e30, &Shot::focus_at),
        keyframes({ "focus-at", "camera", "focus_at", K::Point, G::Camera, "--focus-at X,Y",
                    "Focus on what is seen at display-window pixel X,Y: the median depth of "
                    "the front-most opaque surface over 5x5 pixels (--focus-at-radius); "
                    "keyframes F:X,Y,F:X,Y..." },
                  &Shot::focus_at, 2, -1e7, 1e7, &Shot::focus),
        number({ "focus-at-radius", "camera", "focus_at_radius", K::Number, G::Camera,
                 "--focus-at-radius R",
                 "--focus-at takes the median over (2R+1)x(2R+1) pixels: 0 = the pixel "
                 "alone, larger for noisy depth (default: 2, 5x5)" },
               [](auto& s) -> auto& { return s.focus_at_radius; }, 0, 50),
        number({ "in-focus-range", "camera", "in_focus_range", K::Number, G::Camera,
                 "--in-focus-range METRES",
                 "A depth range around the focus distance that stays sharp, as Nuke "
                 "ZDefocus's depth of field: within METRES/2 of the focus nothing blurs, and "
                 "beyond, the blur grows from the range's ends (default: 0)" },
               [](auto& s) -> auto& { return s.camera.in_focus_range; }, 0, 1e30),
        keyframes({ "focus-tilt", "camera", "focus_tilt", K::Point, G::Camera,
                    "--focus-tilt DEG,DEG",
                    "Tilt the plane of focus (Scheimpflug, the tilt-shift look) about the "
                    "horizontal and the vertical axis through the focus point: positive turns "
                    "its top, and its right side, away from the camera; -80..80; keyframes "
                    "F:A,B,F:A,B... (default: 0,0)" },
                  &Shot::focus_tilt, 2, -80, 80),
        keyframes({ "optical-centre", "camera", "optical_centre", K::Point, G::Camera,
                    "--optical-centre X,Y",
                    "Where the lens's axis meets the image, display-window pixels, for "
                    "--lateral-ca and --cateye (default: the display window's centre)" },
                  &Shot::optical_centre, 2, -1e7, 1e7),
        { { "split-diopter", "camera", "split_diopter", K::Text, G::Camera,
            "--split-diopter %s:X0,Y0,X1,Y1:DIST",
            "A split-field diopter: beyond the line through display-window pixels "
            "X0,Y0 and X1,Y1 (on its right, walking from the first to the second), "
            "focus at DIST, changing over 4 pixels across the line; DIST may be "
            "keyframes F:D,F:D..." },
          parse_split_diopter, print_split_diopter },
    };
}

/// The lens and filmback.
std::vector<SettingRule> lens_rules()
{
    return {
        keyframes({ "focal", "camera", "focal", K::Keyframes, G::Camera, "--focal MM",
                    "Focal length in mm (default: 50)" },
                  &Shot::focal_length_mm, 1, 1e-3, 1e5),
        keyframes({ "fstop", "camera", "fstop", K::Keyframes, G::Camera, "--fstop N",
                    "Aperture f-number (default: 2.8)" },
                  &Shot::fstop, 1, 0.1, 1e4),
        number({ "sensor", "camera", "sensor", K::Number, G::Camera, "--sensor MM",
                 "Horizontal filmback width in mm, spanning the display window (default: "
                 "36)" },
               [](auto& s) -> auto& { return s.camera.sensor_width_mm; }, 1e-3, 1e4),
        choice({ "camera-from-file", "camera", "from_file", K::Switch, G::Camera,
                 "--camera-from-file on|off",
                 "Take the focus, f-number, focal length and filmback a render recorded in "
                 "its header (OpenEXR focus/aperture/camera matrices, Unreal, Arnold, V-Ray) "
                 "where no option or .dof gives them, frame by frame; -v says where each "
                 "value came from (default: on)" },
               [](auto& s) -> auto& { return s.camera_from_file; }, parse_switch, switch_name,
               "value", "on or off"),
        choice({ "lens", "camera", "lens", K::Text, G::Camera, "--lens MODEL",
                 "thin: render cameras, no breathing (default); optical: Potmesil & "
                 "Chakravarty" },
               [](auto& s) -> auto& { return s.camera.lens; }, parse_lens_model,
               lens_model_name, "model", "thin or optical"),
        number({ "max-blur", "camera", "max_blur", K::Number, G::Camera, "--max-blur PX",
                 "Largest CoC diameter in pixels; larger blur is clamped (default: 512)" },
               [](auto& s) -> auto& { return s.camera.max_blur_px; }, 0.0, 1e5),
    };
}

/// The lens's aberrations.
std::vector<SettingRule> lens_effect_rules()
{
    return {
        number({ "axial-ca", "camera", "axial_ca", K::Number, G::Camera, "--axial-ca AMOUNT",
                 "Axial chromatic aberration: red and blue blur 1+AMOUNT times green's in "
                 "front of the focus and 1-AMOUNT times behind it (purple and green bokeh "
                 "rims as a fast lens; nothing in focus fringes), -0.5..0.5 (default: 0)" },
               [](auto& s) -> auto& { return s.camera.axial_ca; }, -0.5, 0.5),
        number({ "lateral-ca", "camera", "lateral_ca", K::Number, G::Camera,
                 "--lateral-ca AMOUNT",
                 "Lateral chromatic aberration: red magnified by 1+AMOUNT and blue by "
                 "1-AMOUNT about the optical centre, in the spread, -0.05..0.05 (default: "
                 "0)" },
               [](auto& s) -> auto& { return s.camera.lateral_ca; }, -0.05, 0.05),
        number({ "cateye", "camera", "cateye", K::Number, G::Camera, "--cateye AMOUNT",
                 "Optical vignetting: towards the edges the bokeh is clipped by a disc "
                 "offset towards the optical centre; 1 = at the farthest corner the clip "
                 "reaches the bokeh's centre; 0..1.5 (default: 0)" },
               [](auto& s) -> auto& { return s.camera.cateye; }, 0.0, 1.5),
    };
}

bool parse_aperture(Shot& shot, const std::string& label, const std::string& value,
                    std::string& error)
{
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
}

/// The bokeh's shape.
std::vector<SettingRule> aperture_rules()
{
    return {
        { { "aperture", "aperture", "shape", K::Text, G::Aperture, "--aperture SHAPE",
            "Bokeh shape: disc (default); polygon (an iris of --blades blades, its "
            "vertices on the CoC circle, as render cameras draw it); mask:FILE (the "
            "shape in an image, thresholded at half its peak, with the disc's area); "
            "box (a square of the disc's area: the fastest); tent and smooth (soft "
            "PSFs of the disc's spread, in constant time)" },
          parse_aperture,
          [](const Shot& shot) {
              return std::string(aperture_shape_name(shot.spread.aperture.shape));
          } },
        text({ "aperture-mask", "aperture", "mask", K::Path, G::Aperture, nullptr,
               "The image of the aperture's shape (set with the shape mask:FILE)" },
             [](auto& s) -> auto& { return s.spread.aperture.mask_file; }),
        number({ "blades", "aperture", "blades", K::Number, G::Aperture, "--blades N",
                 "Polygon: number of blades, 3-16 (default: 6)" },
               [](auto& s) -> auto& { return s.spread.aperture.blades; }, 3, 16),
        number({ "rotation", "aperture", "rotation", K::Number, G::Aperture, "--rotation DEG",
                 "Polygon: rotation clockwise in the image, as Blender/Cycles' aperture "
                 "rotation is given (the same number); 0 = a vertex pointing right "
                 "(default: 0)" },
               [](auto& s) -> auto& { return s.spread.aperture.rotation_deg; }, -3600, 3600),
        number({ "roundness", "aperture", "roundness", K::Number, G::Aperture, "--roundness R",
                 "Polygon: 0 = straight blades, 1 = a disc (default: 0)" },
               [](auto& s) -> auto& { return s.spread.aperture.roundness; }, 0, 1),
        number({ "aspect", "aperture", "aspect", K::Number, G::Aperture, "--aspect A",
                 "The lens's anamorphic squeeze of the bokeh (disc, polygon, mask, box): < 1 "
                 "narrows it horizontally, keeping its area; the plate's own "
                 "pixelAspectRatio is taken from its header (default: 1)" },
               [](auto& s) -> auto& { return s.spread.aperture.aspect; }, 0.05, 20),
    };
}

/// How the bokeh is spread.
std::vector<SettingRule> spread_rules()
{
    return {
        either({ "spread", "aperture", "spread", K::Text, G::Aperture, "--spread METHOD",
                 "Disc, polygon and mask: bounded (default: constant time, large "
                 "footprints merged in blocks of at most r/4 pixels, highlights exact) or "
                 "exact (every pixel on its own: time grows with the blur)" },
               [](auto& s) -> auto& { return s.spread.exact_shape; }, "method",
               std::pair { "bounded", false }, std::pair { "exact", true }),
        text({ "psf-image", "aperture", "psf_image", K::Path, G::Aperture, "--psf-image FILE",
               "The hybrid method: pixels whose bokeh is visible (bright highlights) are "
               "spread with this PSF image, scaled to their CoC; all others with the "
               "fast --aperture filter" },
             [](auto& s) -> auto& { return s.spread.psf_image; }),
        number({ "hybrid-threshold", "aperture", "hybrid_threshold", K::Number, G::Aperture,
                 "--hybrid-threshold T",
                 "Hybrid: a pixel's bokeh is visible when it is T times brighter than the "
                 "mean over its CoC (default: 4)" },
               [](auto& s) -> auto& { return s.spread.hybrid_threshold; }, 1.0, 1e6),
        number({ "aperture-cells", "aperture", "cells", K::Number, G::Aperture,
                 "--aperture-cells N",
                 "Where a near object hides different parts of what lies behind it from "
                 "different points of the lens (a branch's shadow across a far light's "
                 "bokeh), composite the layers per part of the aperture, cut into about N "
                 "cells: 1 = the whole aperture at once (the layered model of compositing "
                 "tools), about half the time where near objects are blurred over detail; "
                 "0 = as many as each place needs (default: 0)" },
               [](auto& s) -> auto& { return s.spread.aperture_cells; }, 0, 256),
    };
}

/// Colour spaces.
std::vector<SettingRule> color_rules()
{
    return {
        text({ "colorconfig", "color", "config", K::Path, G::InputColor, "--colorconfig FILE",
               "OCIO config (default: $OCIO, else the config shipped with defocus)" },
             [](auto& s) -> auto& { return s.color_config; }),
        text({ "iscolorspace", "color", "input", K::Text, G::InputColor, "--iscolorspace NAME",
               "Colour space of the input (default: what the file names: its "
               "colorInteropID, a colour space tag the config has, or the chromaticities of "
               "AP0, AP1, Rec.709, P3-D65 or Rec.2020; else a guess, which -v reports)" },
             [](auto& s) -> auto& { return s.input_space; }),
        text({ "tocolorspace", "color", "output", K::Text, G::OutputColor,
               "--tocolorspace NAME",
               "Colour space of the output (default: the input's), named in its header by "
               "chromaticities and colorInteropID" },
             [](auto& s) -> auto& { return s.output_space; }),
        keyframes({ "bloom", "color", "bloom", K::Point, G::InputColor,
                    "--bloom THRESHOLD,GAIN",
                    "For display-referred plates whose highlights are clipped (sRGB PNG, "
                    "JPEG, Rec.709 video): light whose brightest channel is above THRESHOLD "
                    "in the spreading space is multiplied by GAIN, ramping up from 0.9 "
                    "times THRESHOLD, so that clipped lights make bright bokeh, as "
                    "ZDefocus's bloom does; keyframes F:T,G,F:T,G... (default: off)" },
                  &Shot::bloom, 2, 1e-6, 1e6),
    };
}

bool parse_pixel_type(Shot& shot, const std::string& label, const std::string& value,
                      std::string& error)
{
    if (value == "half" || value == "float" || value.empty()) {
        shot.pixel_type = OIIO::TypeDesc(value);
        return true;
    }
    error = label + ": unknown type '" + value + "' (choose half or float)";
    return false;
}

/// What is written.
std::vector<SettingRule> output_rules()
{
    return {
        choice({ "output", "output", "kind", K::Text, G::Output, "--output KIND",
                 "image: the defocused image (default); focusmap: where the focus falls, "
                 "green in focus, red in front, blue behind, brighter with more blur, "
                 "whitened where the blur reaches --max-blur; layers: the depth layers the "
                 "scene was cut into, each in its own colour (-v lists them), mixed by "
                 "coverage, unblurred" },
               [](auto& s) -> auto& { return s.output; }, parse_output_kind, output_kind_name,
               "kind", "image, focusmap or layers"),
        { { "pixel-type", "output", "type", K::Text, G::Output, "-d TYPE",
            "Output pixel type: half or float (default: the input's)" },
          parse_pixel_type,
          [](const Shot& shot) {
              return shot.pixel_type == OIIO::TypeUnknown ? std::string()
                                                          : std::string(shot.pixel_type.c_str());
          } },
        text({ "compression", "output", "compression", K::Text, G::Output,
               "--compression NAME",
               "Output compression, e.g. zip, piz, dwaa (default: the input's)" },
             [](auto& s) -> auto& { return s.compression; }),
        choice({ "aov", "output", "aov", K::Text, G::Output, "--aov NAME",
                 "Extra channels: confidence, named 'confidence', the fraction of each "
                 "pixel's light that came from surfaces the input hides (behind nearer "
                 "objects of a flat render or deep image) and defocus rebuilt: 0 where all "
                 "of it was seen, as everywhere for layered input; where it is high, look "
                 "closely; then that fraction by how it was rebuilt, in channels named "
                 "confidence.continued (behind an edge), .lines, .patterns and .smooth; "
                 "coc, named 'coc', the signed CoC diameter in pixels (negative in "
                 "front of the focus) of the front-most layer that reaches each pixel, to "
                 "drive other blurs from (default: none)" },
               [](auto& s) -> auto& { return s.aov; }, parse_aov, aov_name, "AOV",
               "none, confidence or coc"),
        { { "data-channels", "output", "data_channels", K::Text, G::Output,
            "--data-channels LIST",
            "Carry the input's data channels through the defocus, not averaged as colour: "
            "auto for every channel whose name says it is data (cryptomatte sets, IDs such "
            "as id or objectId, P, N, Position, Normal) and the depth, written as Z "
            "(coverage-weighted) and ZFront (the front-most layer's); or channel names, "
            "each with :id (the ID with the largest share of the pixel), :dominant (the "
            "value of the layer with the largest share; the default) or :average, beside "
            "auto or not, e.g. auto,matId:id (default: none)" },
          [](Shot& shot, const std::string& label, const std::string& value, std::string& error) {
              std::vector<DataChannelEntry> entries;
              if (!parse_data_channels(label, value, entries, error))
                  return false;
              shot.data_channels = value;
              return true;
          },
          [](const Shot& shot) { return shot.data_channels; } },
        choice({ "deep", "output", "deep", K::Switch, G::Output, nullptr,
                 "A deep OpenEXR result: each layer's defocused RGBA a sample at the "
                 "layer's depths (Z, ZBack), to merge with other elements",
                 { { "--deep", "on",
                     "Write a deep OpenEXR: each layer's defocused R,G,B,A is one sample "
                     "per pixel over the layer's depths (Z, ZBack), so that the result can "
                     "be merged with other elements; flattening it gives the flat result" } } },
               [](auto& s) -> auto& { return s.deep; }, parse_switch, switch_name, "switch",
               "on or off"),
    };
}

/// The result's data window, and what lies beyond the input's.
std::vector<SettingRule> window_rules()
{
    return {
        choice({ "window", "output", "window", K::Text, G::Output, nullptr,
                 "The result's data window: input (the input's, as oiiotool keeps it), "
                 "display or grown (by the blur)",
                 { { "--crop", "display",
                     "Clip the result to the display window (default: the input's data "
                     "window, as oiiotool keeps it)" },
                   { "--grow", "grown",
                     "Grow the data window by the blur, keeping all of the light spread "
                     "beyond the input's data window" } } },
               [](auto& s) -> auto& { return s.window; }, parse_output_window,
               output_window_name, "window", "input, display or grown"),
        choice({ "edge", "scene", "edge", K::Text, G::Output, "--edge MODE",
                 "Beyond the data window: extend (its edge pixels continue outwards, so "
                 "the frame keeps its light to the corners), black (nothing), auto "
                 "(default: extend where the data window does not cover the blur)" },
               [](auto& s) -> auto& { return s.edge; }, parse_edge_mode, edge_mode_name,
               "edge", "auto, extend or black"),
    };
}

}  // namespace

const std::vector<SettingRule>& setting_rules()
{
    static const std::vector<SettingRule> table = [] {
        std::vector<SettingRule> all;
        for (auto section : { sequence_rules, scene_rules, focus_rules, lens_rules,
                              lens_effect_rules, aperture_rules, spread_rules, color_rules,
                              output_rules, window_rules }) {
            std::vector<SettingRule> rules = section();
            all.insert(all.end(), rules.begin(), rules.end());
        }
        return all;
    }();
    return table;
}

}  // namespace defocus
