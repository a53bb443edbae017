// defocus: depth of field for layered scenes, in the style of oiiotool.
//
//   read -> sanitize -> spread each layer -> composite -> write
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <OpenImageIO/argparse.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>
#include <OpenImageIO/sysutil.h>
#include <OpenImageIO/timer.h>

#include <defocus/image_output.h>
#include <defocus/layered_dof.h>
#include <defocus/layering.h>
#include <defocus/scene_io.h>

#include "cli_numbers.h"

using namespace OIIO;
using namespace defocus;

namespace {

struct Options {
    std::vector<std::string> inputs;
    std::string output;
    RenderSettings settings;
    ReadOptions read;
    LayeringOptions layering;
    TypeDesc type = TypeUnknown;
    std::string compression;
    int threads  = 0;
    bool verbose = false;
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
        "layers spaced evenly in CoC. Several INPUTs are the layers of one scene.\n"
        "Each layer is spread with its own per-pixel circle of confusion and\n"
        "the layers are composited back to front. Depth (Z) is planar\n"
        "camera-space depth in metres, as --focus is.");
    ap.epilog(
        "Examples:\n"
        "  defocus shot.exr -o shot_dof.exr --focal 85 --fstop 1.4 --focus 3\n"
        "  defocus shot.exr -o shot_dof.exr --focal 35 --fstop 2.8 --focus 1.2 "
        "--sensor 24.89 --max-blur 100 -d half --compression dwaa -v\n"
        "  defocus shot.exr -o plate.exr --focal 50 --fstop 2 --focus 4 --crop\n"
        "  defocus bg.exr mid.exr fg.exr -o comp.exr --focal 50 --fstop 2 --focus 4\n"
        "  defocus beauty_deep.exr -o out.exr --focal 40 --fstop 2 --focus 6 --layers 24\n"
        "  defocus stereo.exr --view right -o right.exr --focal 35 --fstop 4 --focus 3\n");
    ap.arg("filename").hidden().action([&](cspan<const char*> argv) {
        opt.inputs.emplace_back(argv[0]);
    });

    std::string focal = "50", fstop = "2.8", focus, sensor = "36",
                max_blur = "512", lens = "thin", aperture = "box", type,
                threads = "0", layers = "0";
    auto store = [](std::string& into) {
        return [&into](cspan<const char*> argv) { into = argv[1]; };
    };
    ap.separator("Camera:");
    ap.arg("--focal MM").help("Focal length in mm (default: 50)").action(store(focal));
    ap.arg("--fstop N").help("Aperture f-number (default: 2.8)").action(store(fstop));
    ap.arg("--focus DIST")
        .help("Focus distance in metres (required)")
        .action(store(focus));
    ap.arg("--sensor MM")
        .help("Horizontal filmback width in mm, spanning the display window "
              "(default: 36)")
        .action(store(sensor));
    ap.arg("--lens MODEL")
        .help("thin: render cameras, no breathing (default); optical: "
              "Potmesil & Chakravarty")
        .action(store(lens));
    ap.arg("--max-blur PX")
        .help("Largest CoC diameter in pixels; larger blur is clamped "
              "(default: 512)")
        .action(store(max_blur));
    ap.arg("--aperture SHAPE")
        .help("Bokeh shape: box, a square of the CoC disc's area (default: box)")
        .action(store(aperture));
    ap.separator("Scene:");
    ap.arg("--view NAME")
        .help("View of a multi-view EXR (default: the first part's view)")
        .action(store(opt.read.view));
    ap.arg("--layer NAME")
        .help("Channel prefix of colour and depth, e.g. 'beauty' for beauty.R.."
              "beauty.Z, or Blender's view layer name (default: plain R,G,B,A,Z or "
              "the file's only prefixed set)")
        .action(store(opt.read.layer));
    ap.arg("--layers N")
        .help("Depth layers to cut deep and flat inputs into (default: 0 = "
              "automatic: cut in the gaps between objects, at most 24 px of CoC "
              "per layer)")
        .action(store(layers));
    ap.separator("Output:");
    ap.arg("-o FILE").help("Output file (required); its extension picks the format")
        .action(store(opt.output));
    ap.arg("-d TYPE")
        .help("Output pixel type: half or float (default: the input's)")
        .action(store(type));
    ap.arg("--compression NAME")
        .help("Output compression, e.g. zip, piz, dwaa (default: the input's)")
        .action(store(opt.compression));
    ap.arg("--crop")
        .help("Clip the result to the display window (default: keep the "
              "data window grown by the blur)")
        .action([&](cspan<const char*>) { opt.settings.crop = true; });
    ap.separator("General:");
    ap.arg("-v").help("Verbose: settings, layers, pixel fixes and timings")
        .action([&](cspan<const char*>) { opt.verbose = true; });
    ap.arg("--threads N").help("Worker threads (default: 0 = all cores)")
        .action(store(threads));

    if (ap.parse_args(argc, argv) < 0)
        return ap.geterror();
    if (ap.aborted()) {  // --help
        help_only = true;
        return "";
    }

    std::string error;
    Camera& cam = opt.settings.camera;
    double threads_value = 0, layers_value = 0;
    if (!parse_number("--focal", focal, 1e-3, 1e5, cam.focal_length_mm, error)
        || !parse_number("--fstop", fstop, 0.1, 1e4, cam.fstop, error)
        || !parse_number("--sensor", sensor, 1e-3, 1e4, cam.sensor_width_mm, error)
        || !parse_number("--max-blur", max_blur, 0.0, 1e5, cam.max_blur_px, error)
        || !parse_number("--threads", threads, 0, 1024, threads_value, error)
        || !parse_number("--layers", layers, 0, 256, layers_value, error))
        return error;
    opt.threads = int(threads_value);
    opt.layering.layers = int(layers_value);
    if (layers_value != opt.layering.layers || threads_value != opt.threads)
        return "--threads and --layers take whole numbers";
    if (focus.empty())
        return "--focus DIST is required: the distance of the plane in focus";
    if (!parse_number("--focus", focus, 1e-6, 1e30, cam.focus_distance, error))
        return error;
    if (!parse_lens_model(lens, cam.lens))
        return "--lens: unknown model '" + lens + "' (choose thin or optical)";
    if (!parse_aperture(aperture, opt.settings.aperture))
        return "--aperture: unknown shape '" + aperture + "' (choose box)";
    if (type == "half")
        opt.type = TypeHalf;
    else if (type == "float")
        opt.type = TypeFloat;
    else if (!type.empty())
        return "-d: unknown type '" + type + "' (choose half or float)";
    std::string camera_error = validate(cam);
    if (!camera_error.empty())
        return camera_error;

    if (opt.inputs.empty())
        return "no input file (usage: defocus INPUT -o OUTPUT [options]; see --help)";
    if (opt.output.empty())
        return "no output file: give -o OUTPUT";
    return "";
}

void record_settings(ImageSpec& spec, const RenderSettings& s)
{
    const Camera& c = s.camera;
    spec.attribute("defocus:focalLength", float(c.focal_length_mm));
    spec.attribute("defocus:fNumber", float(c.fstop));
    spec.attribute("defocus:focusDistance", float(c.focus_distance));
    spec.attribute("defocus:filmbackWidth", float(c.sensor_width_mm));
    spec.attribute("defocus:maxBlur", float(c.max_blur_px));
    spec.attribute("defocus:lens", lens_model_name(c.lens));
    spec.attribute("defocus:aperture", aperture_name(s.aperture));
    spec.attribute("Software", "defocus " DEFOCUS_VERSION);
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
    for (const std::string& input : opt.inputs) {
        std::error_code ec;
        if (std::filesystem::equivalent(input, opt.output, ec))
            return fail("{}: the output would overwrite the input", opt.output);
    }
    OIIO::attribute("threads", opt.threads);

    Timer timer;
    auto lap = [&](const char* stage) {
        if (opt.verbose)
            Strutil::print("  {:<10} {:7.3f} s\n", stage, timer.lap());
    };

    Scene scene;
    std::string error;
    if (!read_scene(opt.inputs, opt.read, scene, error))
        return fail("{}", error);
    if (opt.verbose) {
        const Camera& c = opt.settings.camera;
        Strutil::print("defocus {} -> {}\n", scene.source, opt.output);
        Strutil::print("  camera: {} mm f/{} focus {} sensor {} mm, {} lens, "
                       "{} aperture, max blur {} px\n",
                       c.focal_length_mm, c.fstop, c.focus_distance,
                       c.sensor_width_mm, lens_model_name(c.lens),
                       aperture_name(opt.settings.aperture), c.max_blur_px);
        Strutil::print("  display window {}x{}: {} layer(s), {} flat render(s), {} deep image(s)\n",
                       scene.spec.full_width, scene.spec.full_height,
                       scene.layers.size(), scene.flat.size(), scene.deep.size());
    }
    lap("read");

    const PixelCounts fixed = sanitize(scene, opt.threads);
    lap("sanitize");

    const CircleOfConfusion coc(opt.settings.camera, scene.spec.full_width);
    const bool to_slice = !scene.flat.empty() || !scene.deep.empty();
    const LayerBounds bounds = decompose_layers(scene, coc, opt.layering, opt.threads);
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
    if (!render_layered_dof(result, scene, opt.settings, &layers, opt.threads))
        return fail("{}: {}", scene.source, result.geterror());
    lap("render");

    record_settings(result.specmod(), opt.settings);
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
