// layerize: writes the depth layers defocus would use, as a multi-part EXR
// (one part per layer, with Z), for inspection and as input again.
//
//   read -> sanitize -> to scene-linear -> focus -> layers -> write
//
// The first four stages are render_frame's own (prepare_layers).
#include <cstdlib>
#include <string>
#include <vector>

#include <OpenImageIO/argparse.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>

#include <defocus/color/primaries.h>
#include <defocus/error_line.h>
#include <defocus/io/frames.h>
#include <defocus/io/image_output.h>
#include <defocus/io/scene_io.h>
#include <defocus/render_frame.h>

#include "cli_options.h"
#include "process_memory.h"

using namespace OIIO;
using namespace defocus;

namespace {

template<typename... Args>
int fail(const char* fmt, const Args&... args)
{
    Strutil::print(stderr, "layerize: {}\n",
                   error_line(Strutil::fmt::format(fmt, args...), SettingForm::CommandLine));
    return EXIT_FAILURE;
}

}  // namespace

int main(int argc, const char* argv[])
{
    keep_freed_memory();
    remove_temporaries_on_interrupt("layerize");
    Filesystem::convert_native_arguments(argc, argv);
    std::vector<std::string> inputs;
    std::string output;
    bool info = false;
    ShotArguments shot_args;

    ArgParse ap;
    ap.intro("layerize -- the depth layers defocus would use")
        .usage("layerize INPUT [INPUT...] -o OUTPUT.exr [options]\n"
               "   or: layerize --info INPUT [INPUT...] [options]")
        .add_help(false)
        .exit_on_error(false);
    add_help_option(ap);
    ap.description(
        "Reads a scene as defocus does (multi-part, deep or flat RGBA+Z EXR,\n"
        "views, several files) and cuts it into the same depth layers for the\n"
        "same camera. -o writes them as a multi-part EXR, one part per layer\n"
        "with float R,G,B,A,Z, which defocus reads back as the same layers.\n"
        "--info prints one line per layer instead: name, pixel count, depth\n"
        "range and CoC range, back to front.");
    ap.epilog("Examples:\n"
              "  layerize --info deep.exr --focal 85 --fstop 1.4 --focus 3\n"
              "  layerize flat.exr -o layers.exr --focal 85 --fstop 1.4 --focus 3\n"
              "  defocus layers.exr -o out.exr --focal 85 --fstop 1.4 --focus 3\n");
    ap.arg("filename").hidden().action([&](cspan<const char*> a) { inputs.emplace_back(a[0]); });
    shot_args.add_options(ap, OptionGroup::Camera);
    shot_args.add_options(ap, OptionGroup::Scene);
    ap.separator("Colour (OpenColorIO; the layers are cut and written in scene-linear light):");
    shot_args.add_options(ap, OptionGroup::InputColor);
    ap.separator("Output:");
    ap.arg("-o FILE").help("Multi-part EXR to write the layers to")
        .action(shot_args.store_into(output));
    ap.arg("--info").help("Print the layers instead of writing them")
        .action([&](cspan<const char*>) { info = true; });
    ap.separator("General:");
    shot_args.add_threads(ap);
    add_version_option(ap, "layerize");

    if (parse_arguments(ap, argc, argv) < 0)
        return fail("{}", unknown_option_hint(ap, ap.geterror()));
    if (ap.aborted())
        return EXIT_SUCCESS;
    Shot shot;
    shot.inputs = inputs;
    int threads = 0;
    std::string error;
    if (!shot_args.apply(shot, error) || !shot_args.threads(threads, error))
        return fail("{}", error);
    if (inputs.empty())
        return fail("no input file (see --help)");
    if (!check_shot(shot, error))
        return fail("{}", error);
    if (is_animated(shot))
        return fail("layerize renders no frames: give the camera without keyframes");
    if (info == !output.empty())
        return fail("give either -o OUTPUT.exr or --info");
    if (!check_overwrites(files_read(shot, { 0 }), { output }, error))
        return fail("{}", error);
    if (!output.empty() && !check_output(output, "", error))
        return fail("{}", error);
    OIIO::attribute("threads", threads);

    ShotAssets assets;
    LayeredScene layered;
    FrameResult prepared;
    if (!read_shot_assets(shot, assets, error)
        || !prepare_layers(shot, 0, assets, layered, prepared, error, {}, threads))
        return fail("{}", error);

    if (info) {
        for (const LayerReport& l : layered.reports)
            Strutil::print("{:<16} {:>9} px  depth {:.4g}..{:.4g}  CoC {:.3g}..{:.3g} px\n",
                           l.name, l.pixels, l.depth_min, l.depth_max, l.coc_min,
                           l.coc_max);
        return EXIT_SUCCESS;
    }
    ImageSpec spec = layered.spec;
    record_camera(spec, prepared.camera);
    if (prepared.color.config) {  // the layers are in the working space now
        spec.attribute("oiio:ColorSpace", prepared.color.working);
        record_color_space(spec, *prepared.color.config, prepared.color.working);
    }
    if (!write_layers_atomic(layered.layers, spec, output, error))
        return fail("{}", error);
    return EXIT_SUCCESS;
}
