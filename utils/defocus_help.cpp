// What the defocus command says about itself in --help (and so in its man
// page, which help2man makes from --help): what it does, its inputs,
// sequences, scene files and examples.
#include "defocus_help.h"

#include "cli_options.h"

namespace defocus {

void describe_defocus(OIIO::ArgParse& ap)
{
    ap.intro("defocus -- depth of field for layered scenes by constant-time "
             "rectangle spreading\n"
             "(Kosloff, Tao & Barsky, Graphics Interface 2009)")
        .usage("defocus INPUT [INPUT...] -o OUTPUT [options]\n"
               "   or: defocus SHOT.dof -o OUTPUT [options]")
        .add_help(false)
        .exit_on_error(false);
    add_help_option(ap);
    ap.description(
        "INPUT is a layered scene. A multi-part EXR whose parts each hold\n"
        "premultiplied R,G,B,A and Z: the parts are the layers. A deep EXR, or a\n"
        "flat RGBA+Z render (also Blender's ViewLayer.Combined.* with\n"
        "ViewLayer.Depth.Z, or a beauty part and a depth part): cut into depth\n"
        "layers. Several INPUTs are the layers of one scene. Each layer is\n"
        "spread with its own per-pixel circle of confusion and the layers are\n"
        "composited back to front. Depth (Z) is planar camera-space depth in\n"
        "metres, as --focus is (--depth-scale converts other units; --depth-kind\n"
        "reads 1/z, ray distance or a CoC map). A plate whose pixelAspectRatio\n"
        "is not 1 is blurred as its desqueezed image shows it.\n"
        "\n"
        "Sequences use oiiotool's frame patterns: shot.#.exr (4 digits),\n"
        "shot.@@.exr (one digit per @), shot.%04d.exr, or shot.1-100#.exr; the\n"
        "output names its frames the same way. Frames run side by side as the\n"
        "cores and memory allow; a bad frame is reported and the others are\n"
        "still written.\n"
        "\n"
        "A .dof scene file (JSON; the manual's page docs/reference/dof-format.md)\n"
        "holds the inputs and all the settings below; options given with it\n"
        "override its values.");
    ap.epilog(
        "Examples:\n"
        "  defocus shot.exr -o shot_dof.exr --focal 85 --fstop 1.4 --focus 3\n"
        "  defocus render.#.exr --frames 1001-1024 -o dof.#.exr --focal 35 --fstop 2 \\\n"
        "          --focus 1001:3.0,1012:1.2 -d half --compression dwaa\n"
        "  defocus shot.exr --frames 1-24 -o pull.#.exr --focus-at 1:300,160,24:100,150\n"
        "  defocus shot.exr -o focus.png --output focusmap \\\n"
        "          --focal 85 --fstop 1.4 --focus 3\n"
        "  defocus nuke.exr -o out.exr --depth-kind inverse \\\n"
        "          --focal 35 --fstop 2 --focus 4\n"
        "  defocus plate.jpg --depth z.exr -o out.exr --tocolorspace lin_rec709 \\\n"
        "          --focal 35 --fstop 1.8 --focus 2 --bloom 0.9,4\n"
        "  defocus shot.exr --focal 85 --fstop 1.4 --focus 3 --save-scene shot.dof\n"
        "  defocus shot.dof -o out.exr --fstop 2.8\n"
        "  defocus stereo.#.exr --view right -o right.#.exr \\\n"
        "          --focal 35 --fstop 4 --focus 3\n"
        "  defocus bg.exr mid.exr fg.exr -o comp.exr --focal 50 --fstop 2 --focus 4\n");
}

}  // namespace defocus
