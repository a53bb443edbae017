// A shot: everything that says how to render a scene, frame by frame. It is
// what a .dof scene file holds and what the defocus command's options set.
#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

#include <OpenImageIO/typedesc.h>

#include <defocus/optics/aperture.h>
#include <defocus/optics/camera.h>
#include <defocus/optics/depth_kind.h>
#include <defocus/shot/keyframes.h>
#include <defocus/shot/options.h>

namespace defocus {

enum class OutputKind {
    Image,     ///< the defocused image
    FocusMap,  ///< where the focus falls, in false colour (see focus_map)
    Layers,    ///< the layers the scene was cut into, in false colour (see layer_view)
};

/// "image", "focusmap" or "layers"; false for any other name.
bool parse_output_kind(const std::string& name, OutputKind& kind);
const char* output_kind_name(OutputKind kind);

struct Shot {
    /// Files or frame patterns (oiiotool's '#', '@', "%04d"), the layers of
    /// one scene.
    std::vector<std::string> inputs;
    /// Frames to render, e.g. "1001-1100", "1-99x2", "1,5,9-12" ("" = the
    /// frames the input patterns find on disk, or one frame for stills).
    std::string frames;
    /// Frames of a sequence whose input files are missing.
    MissingFrames missing_frames = MissingFrames::Error;
    ReadOptions read;
    /// What the inputs' depth holds; where the shot does not say, a
    /// header's depth_kind_attribute, else planar depth.
    DepthKind depth_kind = DepthKind::Z;
    LayeringOptions layering;
    /// A deep image (or flat RGBA+Z render) of the shot's other elements,
    /// which cuts this one where they stand in front of it: a file or frame
    /// pattern ("" = none).
    std::string holdout;

    /// Focus distance, or the pixel (X,Y in the display window) whose
    /// depth is the focus distance: exactly one is set.
    Keyframes focus, focus_at;
    /// Focusing at a pixel takes the median depth over the square of
    /// 2 focus_at_radius + 1 pixels around it.
    int focus_at_radius = 2;
    /// The plane of focus tilted about the horizontal and the vertical
    /// axis, degrees (Camera::tilt_deg); empty: not tilted.
    Keyframes focus_tilt;
    /// Camera::axis_pixel; empty: the display window's centre.
    Keyframes optical_centre;
    /// A split diopter: its line (x0, y0, x1, y1 in display-window pixels,
    /// see SplitDiopter) and the focus beyond it; empty focus: none.
    struct SplitDiopterSetting {
        std::array<double, 4> line {};
        Keyframes focus;
    } split_diopter;
    /// The camera's settings that may change over the shot, from Camera's
    /// defaults, and those that hold for all of it.
    Keyframes focal_length_mm { Camera().focal_length_mm }, fstop { Camera().fstop };
    CameraBody camera;
    /// Camera values the input's header records (camera_from_header) take
    /// the place of the defaults, frame by frame; given settings win.
    bool camera_from_file = true;

    SpreadOptions spread;

    std::string color_config;  ///< "" = $OCIO, else the shipped config
    std::string input_space;   ///< "" = the file's oiio:ColorSpace, else linear
    std::string output_space;  ///< "" = the input's
    /// Bloom (color/bloom.h): keyframes of (threshold, gain); empty: off.
    Keyframes bloom;

    OutputKind output = OutputKind::Image;
    OIIO::TypeDesc pixel_type = OIIO::TypeUnknown;  ///< unknown = the input's
    std::string compression;                        ///< "" = the input's
    OutputWindow window = OutputWindow::Input;
    Aov aov = Aov::None;
    /// A deep result: each layer's defocused RGBA a sample at its depth.
    bool deep = false;
    /// The input's data channels to carry through (composite/data_channels.h):
    /// "none", "auto", or channel names.
    std::string data_channels = "none";
    EdgeMode edge = EdgeMode::Auto;  ///< beyond the data window, when the blur reaches it

    /// The settings given by set_shot_setting(), each with where (its
    /// label: "--fstop", "camera.fstop", ...).
    std::map<std::string, std::string> given;
};

/// How a setting's value is written in a .dof file.
enum class ShotValueKind {
    Number,     ///< a JSON number
    Keyframes,  ///< a number, or {"frame": number, ...}
    Point,      ///< [x, y], or {"frame": [x, y], ...}
    Text,       ///< a JSON string
    Path,       ///< a JSON string naming a file, relative to the .dof file
    FileOrName, ///< a JSON string: a file as Path when one is there, else a name
    Switch,     ///< "on" or "off" (true or false is read too)
};

/// Where a setting shows in a tool's --help.
enum class OptionGroup {
    Sequences,    ///< which frames
    Camera,       ///< focus, lens and filmback
    Aperture,     ///< the bokeh's shape and how it is spread
    Scene,        ///< what in the input is read, and how it is cut into layers
    InputColor,   ///< the input's colour space
    OutputColor,  ///< the output's colour space
    Output,       ///< what is written
};

/// A command-line switch that sets a setting to one value, such as --crop
/// for window "display".
struct SettingSwitch {
    const char* flag;
    const char* value;
    const char* help;
};

/// One setting of a shot, as every front end names and documents it. Its
/// name is the defocus command's long option without dashes, the Python
/// keyword with '_' for '-', and the plugin hint "dof:NAME".
struct ShotSetting {
    const char* name;
    const char* section;  ///< the .dof object holding it
    const char* key;      ///< its key there
    ShotValueKind kind;
    OptionGroup group;
    /// The command line's option as ArgParse takes it, "--focus DIST" or
    /// "-d TYPE"; nullptr when the setting is given only by switches or
    /// not on the command line.
    const char* option;
    const char* help;
    std::vector<SettingSwitch> switches = {};
};

/// Every setting of a shot except its inputs, in .dof order: the one table
/// the command line, .dof files, Python and the plugin all read.
const std::vector<ShotSetting>& shot_settings();

/// The setting called `name`, or nullptr.
const ShotSetting* find_shot_setting(const std::string& name);

/// Sets the setting `name` from text as the command line writes it, e.g.
/// ("focus", "1:1.25,24:3"), ("aperture", "polygon"), ("crop", "true").
/// Setting one of focus and focus-at clears the other. False, with `error`
/// naming the setting (as `label`, by default a mention of it) and the
/// problem, for an unknown name or a bad value.
bool set_shot_setting(Shot& shot, const std::string& name, const std::string& value,
                      std::string& error, const std::string& label = "");

/// How messages name the setting: by the label it was given with
/// ("--fstop", "camera.fstop"), else by a mention (see setting_words.h).
std::string setting_label(const Shot& shot, const std::string& name);

/// The text set_shot_setting() reads back to the same value ("" when
/// unset).
std::string shot_setting(const Shot& shot, const std::string& name);

/// True when a setting has a value that was given (by set_shot_setting, or
/// set in the struct to other than its default) rather than defaulted.
bool is_given(const Shot& shot, const std::string& name);

/// Where a setting's value comes from: its label when given, "set" when
/// set in the struct, else "default".
std::string setting_origin(const Shot& shot, const std::string& name);

/// True when the shot can be rendered; else false with `error` the first
/// reason it cannot. Reads no file.
bool check_shot(const Shot& shot, std::string& error);

/// The files a shot names: its inputs, the depth file (when the setting
/// names one rather than a channel), the aperture mask, the PSF image and
/// the colour config, as given (frame patterns unfilled).
std::vector<std::string> shot_files(const Shot& shot);

/// The first setting given that a CoC map leaves no meaning to (a focus,
/// a depth scale), as a message saying so; "" for none.
std::string coc_map_conflict(const Shot& shot);

/// True when a setting changes over frames.
bool is_animated(const Shot& shot);

/// The AOV the shot's output carries: an image's, none for a focus map or
/// the layer view.
Aov output_aov(const Shot& shot);

/// The camera at `frame`. Its focus distance is the focus keyframes' (when
/// the shot focuses at a pixel, the caller measures it).
Camera camera_at(const Shot& shot, int frame);

}  // namespace defocus
