#include "io/output_metadata.h"

#include <OpenImageIO/strutil.h>

#include <defocus/color/primaries.h>
#include <defocus/io/frames.h>
#include <defocus/io/image_output.h>
#include <defocus/io/settings_hash.h>
#include <defocus/scene.h>
#include <defocus/shot/setting_words.h>
#include <defocus/version.h>

namespace defocus {

using namespace OIIO;
using Strutil::fmt::format;

namespace {

/// One line of an image's history for this render: the version, the files
/// the frame reads and the settings given, as the defocus command takes
/// them ("--crop", "--aperture mask:FILE").
std::string history_line(const Shot& shot, int frame)
{
    std::string line = format("defocus {}: {}", version(),
                              Strutil::join(files_read(shot, { frame }), " "));
    for (const ShotSetting& setting : shot_settings()) {
        const std::string name = setting.name;
        std::string value = shot_setting(shot, name);
        // A switch's default, given, is the same as none (and has no flag);
        // the mask's file is given with its shape, as mask:FILE.
        if (!is_given(shot, name) || (!setting.option && value == shot_setting(Shot(), name))
            || name == "aperture-mask")
            continue;
        if (name == "aperture" && shot.spread.aperture.shape == ApertureShape::Mask)
            value += ":" + shot.spread.aperture.mask_file;
        if (value.find_first_of(" \t") != std::string::npos)
            value = "'" + value + "'";
        line += " " + setting_words(name, value, SettingForm::CommandLine);
    }
    return line;
}

}  // namespace

void describe_output(ImageSpec& spec, const ImageSpec& input, const Shot& shot,
                     const Camera& camera, DepthKind depth_kind, const ColorPlan& color,
                     int frame)
{
    spec.extra_attribs = input.extra_attribs;
    erase_part_attributes(spec);
    if (shot.output != OutputKind::Image) {
        // A focus map is false colour: it has no colour space.
        spec.erase_attribute("chromaticities");
        spec.erase_attribute("colorInteropID");
    } else if (color.config) {
        spec.attribute("oiio:ColorSpace", color.output);
        record_color_space(spec, *color.config, color.output);
    }
    if (shot.deep)
        spec.attribute("compression",
                       deep_compression(shot.compression, input.get_string_attribute("compression")));
    else if (!shot.compression.empty())
        spec.attribute("compression", shot.compression);
    // A CoC map's camera is only a means to draw its blur.
    if (depth_kind != DepthKind::Coc)
        record_camera(spec, camera);
    spec.erase_attribute(depth_kind_attribute);  // the output has no depth
    const Aperture& aperture = shot.spread.aperture;
    spec.attribute("defocus:aperture", aperture_shape_name(aperture.shape));
    spec.attribute("defocus:aspect", float(aperture.aspect));
    if (aperture.shape == ApertureShape::Mask)
        spec.attribute("defocus:apertureMask", aperture.mask_file);
    if (aperture.shape == ApertureShape::Polygon) {
        spec.attribute("defocus:blades", aperture.blades);
        spec.attribute("defocus:rotation", float(aperture.rotation_deg));
        spec.attribute("defocus:roundness", float(aperture.roundness));
    }
    if (is_sequence(shot))
        spec.attribute("defocus:frame", frame);
    spec.attribute("defocus:settingsHash", settings_hash(shot, frame));
    // Provenance, as oiiotool keeps it: the software that made the input
    // stays named, and the image's history gains how this step was made.
    const std::string ours = std::string("defocus ") + version();
    const std::string software = input.get_string_attribute("Software");
    spec.attribute("Software", software.empty()                    ? ours
                               : Strutil::ends_with(software, ours) ? software
                                                                    : software + "; " + ours);
    std::string history = input.get_string_attribute("Exif:ImageHistory");
    if (!history.empty() && !Strutil::ends_with(history, "\n"))
        history += "\n";
    spec.attribute("Exif:ImageHistory", history + history_line(shot, frame));
}

}  // namespace defocus
