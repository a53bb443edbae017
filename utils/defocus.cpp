// defocus: depth of field for layered scenes, in the style of oiiotool.
//
//   read -> sanitize -> layers -> spread each layer -> composite -> write
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <OpenImageIO/argparse.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>
#include <OpenImageIO/timer.h>

#include <defocus/aperture_profile.h>
#include <defocus/color.h>
#include <defocus/focus_map.h>
#include <defocus/image_output.h>
#include <defocus/layered_dof.h>
#include <defocus/layering.h>
#include <defocus/scene_io.h>

#include "cli_options.h"

using namespace OIIO;
using namespace defocus;

namespace {

struct Options {
    std::vector<std::string> inputs;
    std::string output;
    SceneSettings scene;
    RenderSettings render;
    TypeDesc type = TypeUnknown;
    std::string compression;
    bool verbose = false;
    bool focusmap = false;  ///< --output focusmap
    std::string colorconfig, input_space, output_space;
    std::string preview, display, display_view;
};

template<typename... Args>
int fail(const char* fmt, const Args&... args)
{
    Strutil::print(stderr, "defocus: {}\n", Strutil::fmt::format(fmt, args...));
    return EXIT_FAILURE;
}

// Returns "" on success, or the error message.
std::string parse_command_line(int argc, const char* argv[], Options& opt,
                               bool& help_only)
{
    ArgParse ap;
    ap.intro("defocus -- depth of field for layered scenes by constant-time "
             "rectangle spreading\n"
             "(Kosloff, Tao & Barsky, Graphics Interface 2009)")
        .usage("defocus INPUT [INPUT...] -o OUTPUT [options]")
        .add_help(true)
        .exit_on_error(false);
    ap.description(
        "INPUT is a layered scene. A multi-part EXR whose parts each hold\n"
        "premultiplied R,G,B,A and Z: the parts are the layers. A deep EXR, or a\n"
        "flat RGBA+Z render (also Blender's ViewLayer.Combined.* with\n"
        "ViewLayer.Depth.Z, or a beauty part and a depth part): cut into depth\n"
        "layers. Several INPUTs are the layers of one scene. Each layer is\n"
        "spread with its own per-pixel circle of confusion and the layers are\n"
        "composited back to front. Depth (Z) is planar camera-space depth in\n"
        "metres, as --focus is.");
    ap.epilog(
        "Examples:\n"
        "  defocus shot.exr -o shot_dof.exr --focal 85 --fstop 1.4 --focus 3\n"
        "  defocus shot.exr -o shot_dof.exr --focal 35 --fstop 2.8 --focus 1.2 "
        "--sensor 24.89 --max-blur 100 -d half --compression dwaa -v\n"
        "  defocus shot.exr -o plate.exr --focal 50 --fstop 2 --focus 4 --crop\n"
        "  defocus bg.exr mid.exr fg.exr -o comp.exr --focal 50 --fstop 2 --focus 4\n"
        "  defocus render_deep.exr -o out.exr --focal 40 --fstop 2 --focus 6 --layers 12\n"
        "  defocus stereo.exr --view right -o right.exr --focal 35 --fstop 4 --focus 3\n"
        "  defocus blender.exr --layer ViewLayer -o out.exr --focal 50 --fstop 2 --focus 3\n");
    ap.arg("filename").hidden().action([&](cspan<const char*> argv) {
        opt.inputs.emplace_back(argv[0]);
    });

    SceneArguments scene_args;
    std::string aperture = "disc", type, blades = "6", rotation = "0", roundness = "0",
                aspect = "1", psf_image, hybrid_threshold = "4";
    scene_args.add_camera(ap);
    ap.arg("--aperture SHAPE")
        .help("Bokeh shape, each with the CoC disc's area: disc (default); polygon "
              "(an iris of --blades blades); mask:FILE (the shape in an image, "
              "thresholded at half its peak); box (a square: the fastest); tent and "
              "smooth (soft PSFs of the disc's spread, in constant time)")
        .action(store_into(aperture));
    ap.arg("--blades N").help("Polygon: number of blades, 3-16 (default: 6)")
        .action(store_into(blades));
    ap.arg("--rotation DEG")
        .help("Polygon: counterclockwise rotation; 0 = a vertex pointing right (default: 0)")
        .action(store_into(rotation));
    ap.arg("--roundness R")
        .help("Polygon: 0 = straight blades, 1 = a disc (default: 0)")
        .action(store_into(roundness));
    ap.arg("--aspect A")
        .help("Anamorphic squeeze: < 1 narrows the bokeh horizontally (default: 1)")
        .action(store_into(aspect));
    ap.arg("--psf-image FILE")
        .help("The hybrid method: pixels whose bokeh is visible (bright highlights) "
              "are spread with this PSF image, scaled to their CoC; all others with "
              "the fast --aperture filter")
        .action(store_into(psf_image));
    ap.arg("--hybrid-threshold T")
        .help("Hybrid: a pixel's bokeh is visible when it is T times brighter than "
              "the mean over its CoC (default: 4)")
        .action(store_into(hybrid_threshold));
    scene_args.add_scene(ap);
    ap.separator("Colour (OpenColorIO; spreading happens in scene-linear light):");
    ap.arg("--colorconfig FILE")
        .help("OCIO config (default: $OCIO, else the config shipped with defocus)")
        .action(store_into(opt.colorconfig));
    ap.arg("--iscolorspace NAME")
        .help("Colour space of the input (default: the file's oiio:ColorSpace if the "
              "config has it, else linear)")
        .action(store_into(opt.input_space));
    ap.arg("--tocolorspace NAME")
        .help("Colour space of the output (default: the input's)")
        .action(store_into(opt.output_space));
    ap.arg("--preview FILE")
        .help("Also write an 8-bit display-referred preview (e.g. a .png) of the "
              "display window")
        .action(store_into(opt.preview));
    ap.arg("--display NAME")
        .help("Display for --preview (default: the config's default display)")
        .action(store_into(opt.display));
    ap.arg("--display-view NAME")
        .help("View of that display for --preview (default: the display's default "
              "view; --view is the EXR view of the input)")
        .action(store_into(opt.display_view));
    ap.separator("Output:");
    ap.arg("-o FILE").help("Output file (required); its extension picks the format")
        .action(store_into(opt.output));
    std::string output_kind = "image";
    ap.arg("--output KIND")
        .help("image: the defocused image (default); focusmap: where the focus "
              "falls, green in focus, red in front, blue behind, brighter with more "
              "blur, whitened where the blur reaches --max-blur")
        .action(store_into(output_kind));
    ap.arg("-d TYPE")
        .help("Output pixel type: half or float (default: the input's)")
        .action(store_into(type));
    ap.arg("--compression NAME")
        .help("Output compression, e.g. zip, piz, dwaa (default: the input's)")
        .action(store_into(opt.compression));
    ap.arg("--crop")
        .help("Clip the result to the display window (default: keep the "
              "data window grown by the blur)")
        .action([&](cspan<const char*>) { opt.render.crop = true; });
    ap.separator("General:");
    ap.arg("-v").help("Verbose: settings, layers, pixel fixes and timings")
        .action([&](cspan<const char*>) { opt.verbose = true; });
    scene_args.add_threads(ap);

    if (ap.parse_args(argc, argv) < 0)
        return ap.geterror();
    if (ap.aborted()) {  // --help
        help_only = true;
        return "";
    }

    std::string error;
    if (!scene_args.resolve(opt.scene, error))
        return error;
    opt.render.camera = opt.scene.camera;
    Aperture& a = opt.render.aperture;
    if (Strutil::starts_with(aperture, "mask:")) {
        a.shape = ApertureShape::Mask;
        a.mask_file = aperture.substr(5);
        MaskProfile probe;  // a bad mask fails here, before any reading
        if (!probe.load(a.mask_file, 1.0, 1.0, error))
            return "--aperture: " + error;
    } else if (!parse_aperture_shape(aperture, a.shape) || a.shape == ApertureShape::Mask) {
        return "--aperture: unknown shape '" + aperture
               + "' (choose disc, polygon, mask:FILE, box, tent or smooth)";
    }
    double blade_count = 0;
    if (!parse_number("--blades", blades, 3, 16, blade_count, error)
        || !parse_number("--rotation", rotation, -3600, 3600, a.rotation_deg, error)
        || !parse_number("--roundness", roundness, 0, 1, a.roundness, error)
        || !parse_number("--aspect", aspect, 0.05, 20, a.aspect, error))
        return error;
    a.blades = int(blade_count);
    if (!parse_number("--hybrid-threshold", hybrid_threshold, 1.0, 1e6,
                      opt.render.hybrid_threshold, error))
        return error;
    if (!psf_image.empty()) {
        auto psf = std::make_shared<PsfImage>();
        if (!psf->load(psf_image, error))
            return error;
        opt.render.psf_image = psf;
    }
    if (a.blades != blade_count)
        return "--blades: " + blades + " is not a whole number";
    if (output_kind == "focusmap")
        opt.focusmap = true;
    else if (output_kind != "image")
        return "--output: unknown kind '" + output_kind + "' (choose image or focusmap)";
    if (opt.focusmap && !opt.preview.empty())
        return "--preview does not apply to --output focusmap, which is already a "
               "display image";
    if (type == "half")
        opt.type = TypeHalf;
    else if (type == "float")
        opt.type = TypeFloat;
    else if (!type.empty())
        return "-d: unknown type '" + type + "' (choose half or float)";
    if (opt.inputs.empty())
        return "no input file (usage: defocus INPUT -o OUTPUT [options]; see --help)";
    if (opt.output.empty())
        return "no output file: give -o OUTPUT";
    return "";
}

/// Which colour spaces the pipeline works in.
struct ColourPlan {
    defocus::ColorManagement config;
    bool loaded = false;
    std::string input, working, output;
    std::string to_working;  ///< non-empty when the input must be converted
    std::string summary;     ///< for -v
};

bool plan_colour(const Options& opt, const Scene& scene, ColourPlan& plan,
                 std::string& error)
{
    const bool asked = !opt.colorconfig.empty() || !opt.input_space.empty()
                       || !opt.output_space.empty() || !opt.preview.empty();
    std::string load_error;
    plan.loaded = plan.config.load(opt.colorconfig, load_error);
    if (!plan.loaded) {
        if (asked) {
            error = load_error;
            return false;
        }
        // Without a config, and asked for nothing: the input is linear.
        plan.summary = "colour: no config (" + load_error + "); the input is taken as linear";
        return true;
    }
    const ColorManagement& c = plan.config;
    if (!opt.input_space.empty()) {
        plan.input = c.require_space(opt.input_space, error);
        if (plan.input.empty()) {
            error = "--iscolorspace: " + error;
            return false;
        }
    } else {
        plan.input = c.find_space(scene.spec.get_string_attribute("oiio:ColorSpace"));
    }
    if (!plan.input.empty() && c.is_data(plan.input)) {
        error = Strutil::fmt::format("--iscolorspace: '{}' is data, not colour: the input "
                                     "must be in a colour space",
                                     plan.input);
        return false;
    }
    if (plan.input.empty())
        plan.input = c.scene_linear();  // linear, as far as anyone can tell
    plan.output = plan.input;
    if (!opt.output_space.empty()) {
        plan.output = c.require_space(opt.output_space, error);
        if (plan.output.empty()) {
            error = "--tocolorspace: " + error;
            return false;
        }
    }
    // Spreading commutes with the 3x3 matrix between two linear spaces, so
    // a linear input is spread as it is.
    if (c.is_linear(plan.input)) {
        plan.working = plan.input;
    } else {
        plan.working = c.scene_linear();
        plan.to_working = plan.working;
    }
    plan.summary = Strutil::fmt::format(
        "colour: config {} ({}); input '{}', spread in '{}', output '{}'", c.path(),
        c.origin(), plan.input, plan.working, plan.output);
    return true;
}

bool write_preview(const ImageBuf& result, const ColourPlan& colour, const Options& opt,
                   std::string& error)
{
    const ColorManagement& c = colour.config;
    const std::string display = opt.display.empty() ? c.default_display() : opt.display;
    const std::string view = opt.display_view.empty() ? c.default_view(display)
                                                      : opt.display_view;
    const ImageSpec& spec = result.spec();
    ImageBuf framed, shown;
    ImageBufAlgo::crop(framed, result,
                       ROI(spec.full_x, spec.full_x + spec.full_width, spec.full_y,
                           spec.full_y + spec.full_height, 0, 1, 0, spec.nchannels));
    if (!c.display(shown, framed, colour.working, display, view, error)) {
        error = "--preview: " + error;
        return false;
    }
    return write_image_atomic(shown, opt.preview, TypeUInt8, "", error);
}

TypeDesc input_color_type(const ImageSpec& spec)
{
    const int r = spec.channelindex("R");
    return r >= 0 ? spec.channelformat(r) : spec.format;
}

}  // namespace

int main(int argc, const char* argv[])
{
    Filesystem::convert_native_arguments(argc, argv);
    Options opt;
    bool help_only = false;
    const std::string usage_error = parse_command_line(argc, argv, opt, help_only);
    if (help_only)
        return EXIT_SUCCESS;
    if (!usage_error.empty())
        return fail("{}", usage_error);
    for (const std::string& input : opt.inputs)
        for (const std::string& written : { opt.output, opt.preview }) {
            std::error_code ec;
            if (std::filesystem::equivalent(input, written, ec))
                return fail("{}: the output would overwrite the input", written);
        }
    const int threads = opt.scene.threads;
    OIIO::attribute("threads", threads);

    Timer timer;
    auto lap = [&](const char* stage) {
        if (opt.verbose)
            Strutil::print("  {:<10} {:7.3f} s\n", stage, timer.lap());
    };

    Scene scene;
    std::string error;
    if (!read_scene(opt.inputs, opt.scene.read, scene, error))
        return fail("{}", error);
    if (opt.verbose) {
        const Camera& c = opt.render.camera;
        Strutil::print("defocus {} -> {}\n", scene.source, opt.output);
        Strutil::print("  camera: {} mm f/{} focus {} sensor {} mm, {} lens, "
                       "{} aperture, max blur {} px\n",
                       c.focal_length_mm, c.fstop, c.focus_distance,
                       c.sensor_width_mm, lens_model_name(c.lens),
                       aperture_shape_name(opt.render.aperture.shape), c.max_blur_px);
        Strutil::print("  display window {}x{}: {} layer(s), {} flat render(s), "
                       "{} deep image(s)\n",
                       scene.spec.full_width, scene.spec.full_height,
                       scene.layers.size(), scene.flat.size(), scene.deep.size());
    }
    lap("read");

    const PixelCounts fixed = sanitize(scene, threads);
    lap("sanitize");

    ColourPlan colour;
    if (!plan_colour(opt, scene, colour, error))
        return fail("{}", error);
    if (opt.verbose)
        Strutil::print("  {}\n", colour.summary);
    if (!colour.to_working.empty()
        && !convert_scene(scene, colour.config, colour.input, colour.working, error, threads))
        return fail("{}: {}", scene.source, error);
    lap("colour");

    const CircleOfConfusion coc(opt.render.camera, scene.spec.full_width);
    const bool to_slice = !scene.flat.empty() || !scene.deep.empty();
    const LayerBounds bounds = decompose_layers(scene, coc, opt.scene.layering, threads);
    if (opt.verbose && to_slice) {
        std::vector<std::string> edges;
        for (int k = 0; k <= bounds.count(); ++k)
            edges.push_back(Strutil::fmt::format("{:.3g}", bounds.boundary(k)));
        Strutil::print("  sliced into {} depth layer(s), bounds in px of CoC: {}\n",
                       bounds.count(), Strutil::join(edges, " "));
    }
    lap("slice");

    ImageBuf result;
    std::vector<LayerReport> layers;
    if (opt.focusmap) {
        if (!focus_map(result, scene, opt.render.camera, 8.0, threads))
            return fail("{}: {}", scene.source, result.geterror());
        result.specmod().extra_attribs = scene.spec.extra_attribs;
        erase_part_attributes(result.specmod());
        lap("focus map");
    } else {
        if (!render_layered_dof(result, scene, opt.render, &layers, threads))
            return fail("{}: {}", scene.source, result.geterror());
        lap("render");
    }

    if (!opt.preview.empty()) {
        if (!write_preview(result, colour, opt, error))
            return fail("{}", error);
        lap("preview");
    }
    if (colour.loaded && !opt.focusmap) {  // a focus map is false colour
        if (!colour.config.convert(result, colour.working, colour.output, error, threads))
            return fail("{}: {}", opt.output, error);
        result.specmod().attribute("oiio:ColorSpace", colour.output);
    }
    record_camera(result.specmod(), opt.render.camera);
    const Aperture& aperture = opt.render.aperture;
    result.specmod().attribute("defocus:aperture", aperture_shape_name(aperture.shape));
    result.specmod().attribute("defocus:aspect", float(aperture.aspect));
    if (aperture.shape == ApertureShape::Mask)
        result.specmod().attribute("defocus:apertureMask", aperture.mask_file);
    if (aperture.shape == ApertureShape::Polygon) {
        result.specmod().attribute("defocus:blades", aperture.blades);
        result.specmod().attribute("defocus:rotation", float(aperture.rotation_deg));
        result.specmod().attribute("defocus:roundness", float(aperture.roundness));
    }
    result.specmod().attribute("Software", "defocus " DEFOCUS_VERSION);
    const TypeDesc type = opt.type != TypeUnknown ? opt.type
                                                  : input_color_type(scene.spec);
    if (!write_image_atomic(result, opt.output, type, opt.compression, error))
        return fail("{}", error);
    lap("write");

    if (opt.verbose) {
        Strutil::print("  layers, back to front:\n");
        for (const LayerReport& l : layers)
            Strutil::print("    {:<12} {:>9} px  depth {:.4g}..{:.4g}  CoC {:.3g}..{:.3g} px\n",
                           l.name, l.pixels, l.depth_min, l.depth_max,
                           l.coc_min, l.coc_max);
        if (opt.render.psf_image) {
            int64_t slow = 0, covered = 0;
            for (const LayerReport& l : layers) {
                slow += l.psf_pixels;
                covered += l.pixels;
            }
            Strutil::print("  hybrid: {} of {} pixels ({:.2f}%) spread with the PSF image\n",
                           slow, covered, covered ? 100.0 * slow / covered : 0.0);
        }
        Strutil::print("  pixels fixed: {} with NaN/inf colour dropped, {} with "
                       "bad depth taken as infinitely far, {} transparent with "
                       "colour cleared\n",
                       fixed.nonfinite_color, fixed.bad_depth,
                       fixed.transparent_light);
        Strutil::print("  wrote {} ({}x{} data window, {})\n", opt.output,
                       result.spec().width, result.spec().height, type);
    }
    return EXIT_SUCCESS;
}
