// The defocus tool end to end: a generated multi-part scene, and every bad
// input ending in a one-line error, a non-zero exit and no output file.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <regex>
#include <tuple>
#include <set>

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include <defocus/version.h>

#include "test_support.h"

using namespace defocus_test;
using namespace OIIO;
using Strutil::fmt::format;

namespace {

const std::string camera = " --focal 50 --fstop 1.8 --focus 4";

/// Whether this build runs under AddressSanitizer, whose shadow memory and
/// quarantine a process's peak holds and no estimate of ours counts.
#if defined(__SANITIZE_ADDRESS__)
constexpr bool under_address_sanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool under_address_sanitizer = true;
#else
constexpr bool under_address_sanitizer = false;
#endif
#else
constexpr bool under_address_sanitizer = false;
#endif

/// Writes to `flat` a flat render of the example scene `layered`: its parts
/// (sky, hills, post, leaves) composited back to front, with the depth of
/// the front-most surface.
void flatten_example(const std::string& layered, const std::string& flat)
{
    ImageBuf flat_color, flat_depth;
    for (int part = 0; part < 4; ++part) {
        ImageBuf p(layered, part, 0);
        REQUIRE(p.read(part, 0, true, TypeFloat));
        ImageBuf rgba = ImageBufAlgo::channels(p, 4, { 0, 1, 2, 3 });
        ImageBuf z = ImageBufAlgo::channels(p, 1, { 4 });
        rgba.specmod().alpha_channel = 3;
        if (part == 0) {
            flat_color = rgba;
            flat_depth = z;
            continue;
        }
        for (ImageBuf::Iterator<float> c(flat_color), d(flat_depth); !c.done(); ++c, ++d) {
            float s[4], sz;
            rgba.getpixel(c.x(), c.y(), s);
            z.getpixel(c.x(), c.y(), &sz, 1);
            for (int i = 0; i < 4; ++i)
                c[i] = s[i] + (1 - s[3]) * c[i];
            if (s[3] > 0.5f)
                d[0] = sz;
        }
    }
    ImageBuf both = ImageBufAlgo::channel_append(flat_color, flat_depth);
    both.specmod().channelnames = { "R", "G", "B", "A", "Z" };
    REQUIRE(both.write(flat));
}

/// Runs defocus; the output and exit status.
int run_defocus(const std::string& args, std::string& output)
{
    return run(defocus_bin + " " + args, output);
}

size_t count_of(const std::string& text, const std::string& what)
{
    size_t n = 0;
    for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1))
        ++n;
    return n;
}

}  // namespace

TEST_CASE("defocus renders a generated multi-part scene")
{
    const std::string dir = scratch_dir("cli_scene");
    const std::string out = dir + "/out.exr";
    std::string log;
    REQUIRE(run_defocus(example_scene() + " -o " + out + camera + " -v", log) == 0);
    CHECK(Strutil::contains(log, "leaves"));
    CHECK(Strutil::contains(log, "layers, back to front"));
    // By default the layers are composited per part of the lens where a
    // near one hides different parts of a far one; -v says where.
    CHECK(Strutil::contains(log, "composited per part of the lens, in up to 16 cells"));
    std::string whole;
    REQUIRE(run_defocus(example_scene() + " -o " + scratch_dir("cli_cells") + "/out.exr" + camera
                            + " --aperture-cells 1 -v",
                        whole)
            == 0);
    CHECK_FALSE(Strutil::contains(whole, "sub-aperture"));

    const ImageSpec spec = read_spec(out), input = read_spec(example_scene());
    // The display window and metadata of the input, the camera recorded.
    CHECK(spec.full_width == 320);
    CHECK(spec.full_height == 180);
    CHECK(spec.nchannels == 4);
    CHECK(spec.format == TypeHalf);
    CHECK(spec.get_float_attribute("defocus:focalLength") == 50.0f);
    CHECK(spec.get_float_attribute("defocus:fNumber") == 1.8f);
    CHECK(spec.get_float_attribute("defocus:focusDistance") == 4.0f);
    CHECK(spec.get_string_attribute("defocus:aperture") == "disc");  // the default
    CHECK(spec.get_string_attribute("defocus:exampleCamera") != "");
    CHECK(spec.get_string_attribute("compression") == "zip");
    // The input's data window, as oiiotool's filters keep it.
    CHECK(spec.x == input.x);
    CHECK(spec.width == input.width);
    CHECK(spec.height == input.height);
    CHECK(no_nan(read_image(out)));

    // --grow keeps the light spread beyond the input's overscan.
    const std::string grown = dir + "/grown.exr";
    REQUIRE(run_defocus(example_scene() + " -o " + grown + camera + " --grow", log) == 0);
    const ImageSpec g = read_spec(grown);
    CHECK(g.x < input.x);
    CHECK(g.width > input.width);

    // --crop clips to the display window; -d and --compression are obeyed.
    const std::string cropped = dir + "/cropped.exr";
    REQUIRE(run_defocus(example_scene() + " -o " + cropped + camera
                        + " --crop -d float --compression piz", log) == 0);
    const ImageSpec c = read_spec(cropped);
    CHECK(c.x == 0);
    CHECK(c.width == 320);
    CHECK(c.format == TypeFloat);
    CHECK(c.get_string_attribute("compression") == "piz");
    // No temporary files are left beside the outputs.
    std::vector<std::string> files;
    Filesystem::get_directory_entries(dir, files);
    CHECK(files.size() == 3);
}

TEST_CASE("a deep result is written as a deep EXR: half colour, float depths, zips, known to "
          "--skip-existing")
{
    const std::string dir = scratch_dir("cli_deep");
    const std::string out = dir + "/deep.exr";
    std::string log;
    REQUIRE(run_defocus(example_scene() + " -o " + out + camera + " --deep", log) == 0);
    const ImageSpec spec = read_spec(out);
    CHECK(spec.deep);
    REQUIRE(spec.nchannels == 6);
    CHECK(spec.channelformat(0) == TypeHalf);  // the input's, as for a flat result
    CHECK(spec.channelformat(4) == TypeFloat);
    // The example's zip becomes zips, which deep files are written with.
    CHECK(spec.get_string_attribute("compression") == "zips");
    // The deep image's making is a stage of its own, not "colour out".
    REQUIRE(run_defocus(example_scene() + " -o " + dir + "/timed.exr" + camera + " --deep -v",
                        log) == 0);
    CHECK(count_of(log, "  deep image ") == 1);
    CHECK_THAT(spec.get_string_attribute("Exif:ImageHistory"), Catch::EndsWith(" --deep"));
    REQUIRE(run_defocus(example_scene() + " -o " + out + camera + " --deep --skip-existing",
                        log) == 0);
    CHECK_THAT(log, Catch::Contains("skipped"));

    // Flattened, the file is the flat file: to 1e-5 in float; in half, each
    // sample is rounded on its own (the manual says so).
    auto difference = [&](const std::string& type) {
        REQUIRE(run_defocus(example_scene() + " -o " + dir + "/d.exr" + camera + " --deep -d "
                                + type,
                            log) == 0);
        REQUIRE(run_defocus(example_scene() + " -o " + dir + "/f.exr" + camera + " -d " + type,
                            log) == 0);
        const ImageBuf flattened
            = ImageBufAlgo::channels(ImageBufAlgo::flatten(ImageBuf(dir + "/d.exr")), 4, {});
        return ImageBufAlgo::compare(flattened, ImageBuf(dir + "/f.exr"), 0.0f, 0.0f).maxerror;
    };
    CHECK(difference("float") < 1e-5);
    const double in_half = difference("half");
    WARN("deep half, flattened, against the flat half file: " << in_half);
    CHECK(in_half < 1e-2);  // the example's lights reach 8: half rounds them by 4e-3
}

TEST_CASE("a mistyped option is answered with the nearest one")
{
    std::string log;
    const std::string scene = example_scene() + " -o " + scratch_dir("cli_typo") + "/o.exr ";
    const struct {
        std::string args, said;
    } cases[] = {
        { "--focsu 3", "Invalid option \"--focsu\": did you mean --focus?" },
        { "--memroy-limit 1G", "did you mean --memory-limit?" },
        { "--foacl 50", "did you mean --focal?" },
        { "--wibble 3", "Invalid option \"--wibble\" (see --help)" },
    };
    for (const auto& c : cases) {
        INFO(c.args);
        CHECK(run_defocus(scene + c.args, log) != 0);
        CHECK_THAT(log, Catch::Contains(c.said));
        CHECK(count_of(log, "\n") == 1);
    }
    REQUIRE(run(format("{} {} -o x.exr --layres 3", LAYERIZE_BIN, example_scene()), log) != 0);
    CHECK_THAT(log, Catch::Contains("did you mean --layers?"));
}

TEST_CASE("every bad input ends in a one-line error and no output")
{
    const std::string dir = scratch_dir("cli_errors");
    const std::string out = dir + "/out.exr";
    const std::string not_image = dir + "/notes.exr";
    Filesystem::write_text_file(not_image, "this is not an image\n");
    const std::string no_colour = dir + "/no_colour.exr";
    write_uniform_image(no_colour, { "R", "G", "Z" }, { 1, 1, 2 });
    const std::string no_depth = dir + "/no_depth.exr";
    write_uniform_image(no_depth, { "R", "G", "B", "A" }, { 1, 1, 1, 1 });
    const std::string with_coc = dir + "/with_coc.exr";
    write_uniform_image(with_coc, { "R", "G", "B", "A", "Z", "ZFront", "coc" },
                        { 1, 1, 1, 1, 3, 3, 2 });

    struct Case {
        std::string args, mentions;
    };
    const std::vector<Case> cases = {
        { dir + "/missing.exr -o " + out + camera, "missing.exr: no such file" },
        { not_image + " -o " + out + camera, "notes.exr" },
        { no_colour + " -o " + out + camera, "no B channel" },
        { no_depth + " -o " + out + camera, "no Z channel" },
        { no_depth + " -o " + out + camera + " --depth depth.Z", "--depth depth.Z: no such channel" },
        // --depth is the input's: a holdout without depths is told what a
        // holdout takes.
        { example_scene() + " -o " + out + camera + " --holdout " + no_depth,
          "no_depth.exr: part 0 has no Z channel (channels: R,G,B,A): --holdout takes a deep "
          "EXR or a flat render with a Z channel" },
        { example_scene() + " -o " + out + " --focal 50 --fstop abc --focus 4",
          "--fstop: 'abc' is not a number" },
        { example_scene() + " -o " + out + " --focal 50 --fstop 1.8 --focus -2",
          "--focus" },
        { example_scene() + " -o " + out + " --focal 50 --fstop 0 --focus 4",
          "out of range" },
        { example_scene() + " -o " + out + camera + " --max-blur 1e9", "--max-blur" },
        { example_scene() + " -o " + out + camera + " --threads x", "--threads" },
        { example_scene() + " -o " + out + camera + " --aperture heart", "heart" },
        { example_scene() + " -o " + out + camera + " --blades 2", "--blades" },
        { example_scene() + " -o " + out + camera + " --output depth", "--output: unknown kind 'depth'" },
        { example_scene() + " -o " + out + camera + " --output focusmap --preview " + dir + "/p.png",
          "--preview does not apply" },
        { example_scene() + " -o " + out + camera + " --aov depth", "--aov: unknown AOV 'depth'" },
        { example_scene() + " -o " + out + camera + " --output focusmap --aov confidence",
          "--aov applies to the defocused image" },
        { example_scene() + " -o " + out + camera + " --aperture mask:" + dir + "/no_mask.png",
          "no_mask.png: cannot read the aperture mask" },
        { example_scene() + " -o " + out + camera + " --psf-image " + dir + "/no_psf.exr",
          "no_psf.exr: cannot read the PSF image" },
        { example_scene() + " -o " + out + camera + " --hybrid-threshold 0.5", "--hybrid-threshold" },
        { example_scene() + " -o " + out + camera + " -d int7", "int7" },
        { example_scene() + " -o " + out + " --focal 50", "--focus" },
        { example_scene() + camera, "-o" },
        { example_scene() + " -o " + out + camera + " --bogus", "bogus" },
        // The output is checked before any frame is rendered: one line, even
        // for a sequence, naming the user's path and not a temporary file.
        { example_scene() + " -o " + dir + "/no/such/dir/out.exr" + camera,
          "out.exr: the folder " + dir + "/no/such/dir does not exist" },
        { example_scene() + " --frames 1-3 -o " + dir + "/no/such/dir/out.#.exr" + camera,
          "out.0001.exr: the folder" },
        { example_scene() + " -o " + dir + "/out.xyz" + camera, "no image format writes .xyz files" },
        { example_scene() + " -o " + out + camera + " --compression bogus",
          "out.exr: unknown openexr compression 'bogus'" },
        { example_scene() + " -o " + dir + "/out.png" + camera + " --compression piz",
          "unknown png compression 'piz'" },
        { example_scene() + " -o " + out + camera + " --preview " + dir + "/./out.exr",
          "-o and --preview name the same file" },
        // What a deep result cannot hold.
        { example_scene() + " -o " + dir + "/out.tif" + camera + " --deep",
          "out.tif: a deep result is written as OpenEXR (.exr), not tiff" },
        { example_scene() + " -o " + out + camera + " --deep --compression zip",
          "out.exr: deep OpenEXR takes no compression 'zip' (known: none, zips)" },
        { example_scene() + " -o " + out + camera + " --deep --aov coc",
          "--aov cannot be written with --deep" },
        { example_scene() + " -o " + out + camera + " --deep --lateral-ca 0.01",
          "--lateral-ca cannot be written with --deep" },
        { example_scene() + " -o " + out + camera + " --deep --output focusmap",
          "--deep writes the defocused image, not --output focusmap" },
        // Data channels the input lacks, or of an unknown kind.
        { example_scene() + " -o " + out + camera + " --data-channels auto,matId",
          "--data-channels auto,matId: the input has no channel matId" },
        { example_scene() + " -o " + out + camera + " --data-channels Z:sum",
          "--data-channels: unknown kind 'sum' for channel Z" },
        // Channels of one name, and formats that cannot name channels:
        // refused before rendering, never written as channelN or dropped.
        { with_coc + " -o " + out + camera + " --aov coc --data-channels auto,coc:average",
          "--data-channels auto,coc:average: the data channel coc and --aov coc would both be "
          "written as channel coc" },
        { with_coc + " -o " + out + camera + " --data-channels Z,ZFront:average",
          "--data-channels Z,ZFront:average: the data channel ZFront and the data channel Z's "
          "ZFront would both be written as channel ZFront" },
        { example_scene() + " -o " + dir + "/out.tif" + camera + " --aov coc",
          "out.tif: tiff files do not keep channel names, which --aov coc needs: write OpenEXR "
          "(.exr)" },
        { example_scene() + " -o " + dir + "/out.png" + camera + " --aov coc",
          "out.png: png files do not keep channel names" },
        { example_scene() + " -o " + dir + "/out.jpg" + camera + " --data-channels auto",
          "out.jpg: jpeg files do not keep channel names, which --data-channels auto needs" },
        // Renderers' conventions: bad kinds and values, and a focus on a
        // CoC map.
        { example_scene() + " -o " + out + camera + " --depth-kind far",
          "--depth-kind: unknown depth kind 'far' (choose z, inverse, distance or coc)" },
        { example_scene() + " -o " + out + camera + " --depth-kind coc",
          "--focus has no meaning for a depth that is a CoC map (--depth-kind coc)" },
        { example_scene() + " -o " + out + camera + " --bloom 0.9", "--bloom: '0.9' is not" },
        { example_scene() + " -o " + out + camera + " --bloom 0,4", "--bloom: 0 is out of range" },
        { example_scene() + " -o " + out + camera + " --output layers --aov coc",
          "--aov applies to the defocused image, not to --output layers" },
        // Conflicting or unused options.
        { example_scene() + " -o " + out + camera + " --crop --grow",
          "--crop and --grow contradict each other" },
        { example_scene() + " -o " + out + camera + " --blades 5",
          "--blades applies only to --aperture polygon (the aperture is disc)" },
        { example_scene() + " -o " + out + " -o " + dir + "/other.exr" + camera,
          "-o given twice" },
        { example_scene() + " -o " + out + camera + " --focus 2", "--focus given twice" },
        { example_scene() + " -o " + example_scene() + camera, "overwrite the input" },
    };
    for (const Case& c : cases) {
        INFO("defocus " << c.args);
        std::string log;
        const int status = run_defocus(c.args, log);
        INFO(log);
        CHECK(status != 0);
        CHECK(status < 128);  // exited, not killed by a signal
        CHECK(one_line_naming(log, c.mentions));
        CHECK_FALSE(Filesystem::exists(out));
    }
    std::vector<std::string> files;
    Filesystem::get_directory_entries(dir, files);
    CHECK(files.size() == 4);  // only the inputs written above
}

TEST_CASE("options take --option=value as well as --option value")
{
    const std::string dir = scratch_dir("cli_equals");
    std::string log;
    REQUIRE(run_defocus(example_scene() + " -o " + dir + "/equals.exr -d float --focal=50 "
                            "--fstop=1.8 --focus=4 --aperture=polygon --blades=6",
                        log) == 0);
    REQUIRE(run_defocus(example_scene() + " -o " + dir + "/polygon.exr -d float" + camera
                            + " --aperture polygon",
                        log) == 0);
    const ImageBuf equals = read_image(dir + "/equals.exr"),
                   polygon = read_image(dir + "/polygon.exr");
    CHECK(ImageBufAlgo::compare(equals, polygon, 0.0f, 0.0f).maxerror == 0.0);

    // A lone "--" ends the options: what follows is a file, even "-x.exr".
    REQUIRE(Filesystem::copy(example_scene(), dir + "/-scene.exr"));
    REQUIRE(run(format("cd {} && {} -o ended.exr -d float{} --aperture polygon -- -scene.exr",
                       dir, DEFOCUS_BIN, camera),
                log)
            == 0);
    CHECK(ImageBufAlgo::compare(read_image(dir + "/ended.exr"), polygon, 0.0f, 0.0f).maxerror
          == 0.0);
}

TEST_CASE("the help teaches the options")
{
    std::string log;
    REQUIRE(run_defocus("--help", log) == 0);
    for (const char* option : { "--focal", "--fstop", "--focus", "--sensor", "--lens",
                                "--max-blur", "--aperture", "--blades", "--rotation", "--roundness",
                                "--aspect", "--psf-image", "--hybrid-threshold", "-o", "--output", "-d",
                                "--compression",
                                "--crop", "-v", "--threads", "Examples" })
        CHECK(Strutil::contains(log, option));
    // It fits the terminal (COLUMNS where stdout is not one), each option's
    // help wrapped under its column, and no wrapped line reads as an option.
    for (const char* tool : { DEFOCUS_BIN, LAYERIZE_BIN })
        for (const int columns : { 60, 80, 132 }) {
            INFO(tool << ", " << columns << " columns");
            REQUIRE(run(format("COLUMNS={} {} --help", columns, tool), log) == 0);
            size_t longest = 0, options = 0;
            for (const std::string& line : Strutil::splits(log, "\n")) {
                longest = std::max(longest, line.size());
                options += Strutil::starts_with(line, "    -");
            }
            CHECK(longest < size_t(columns));
            CHECK(options >= 25);
        }
    std::string wide;
    REQUIRE(run(format("COLUMNS=1000 {} --help", DEFOCUS_BIN), wide) == 0);
    const auto lines = [](const std::string& text, const char* start) {
        size_t n = 0;
        for (const std::string& line : Strutil::splits(text, "\n"))
            n += Strutil::starts_with(line, start);
        return n;
    };
    REQUIRE(run(format("COLUMNS=60 {} --help", DEFOCUS_BIN), log) == 0);
    CHECK(lines(log, "    -") == lines(wide, "    -"));
}

TEST_CASE("layerize writes the layers defocus uses, and defocus reads them back")
{
    const std::string dir = scratch_dir("cli_layerize");
    const std::string layerize = LAYERIZE_BIN;
    // A flat render: the example scene's layers flattened, with the depth
    // of the front-most surface.
    const std::string flat = dir + "/flat.exr";
    std::string log;
    REQUIRE(run(layerize + " " + example_scene() + camera + " -o " + dir + "/given.exr", log) == 0);
    ImageBuf scene(example_scene());
    flatten_example(example_scene(), flat);
    // -v names as many layers as it says the input was sliced into, even
    // when some slices are empty.
    REQUIRE(run_defocus(flat + " -o " + dir + "/v.exr -v --layers 12" + camera, log) == 0);
    std::smatch sliced;
    REQUIRE(std::regex_search(log, sliced, std::regex("sliced into ([0-9]+) depth layer")));
    const std::regex layer_line("\n    \\S+ +[0-9]+ px  depth");
    const auto listed = std::distance(std::sregex_iterator(log.begin(), log.end(), layer_line),
                                      std::sregex_iterator());
    CHECK(listed == std::stoi(sliced[1]));
    CHECK(Strutil::contains(log, "empty slice(s) dropped"));
    const std::string layers = dir + "/layers.exr";
    REQUIRE(run(layerize + " " + flat + camera + " -o " + layers, log) == 0);
    REQUIRE(run_defocus(flat + " -o " + dir + "/direct.exr -d float" + camera, log) == 0);
    REQUIRE(run_defocus(layers + " -o " + dir + "/via_layers.exr -d float" + camera, log) == 0);
    const ImageBuf direct = read_image(dir + "/direct.exr");
    const ImageBuf via = read_image(dir + "/via_layers.exr");
    REQUIRE(direct.initialized());
    REQUIRE(via.initialized());
    CHECK(direct.roi() == via.roi());
    CHECK(worst_relative_error(via, direct, 0.0, 1e-6) <= 1.0);

    // --info: one line per layer, the same layers the file holds.
    REQUIRE(run(layerize + " --info " + flat + camera, log) == 0);
    const int nparts = count_subimages(layers);
    CHECK(std::count(log.begin(), log.end(), '\n') == nparts);
    CHECK(Strutil::contains(log, "depth"));
    CHECK(Strutil::contains(log, "CoC"));
}

TEST_CASE("layerize cuts in scene-linear light, as defocus spreads")
{
    // A flat sRGB-encoded grey card at 3 m: the layers hold its linear light.
    const std::string dir = scratch_dir("cli_layerize_colour");
    ImageBuf card = zero_image(ROI(0, 16, 0, 8), 5);
    ImageBufAlgo::fill(card, { 0.5f, 0.5f, 0.5f, 1.0f, 3.0f });
    card.specmod().channelnames = { "R", "G", "B", "A", "Z" };
    card.specmod().alpha_channel = 3;
    card.specmod().z_channel = 4;
    REQUIRE(card.write(dir + "/card.exr"));
    std::string log;
    INFO(log);
    REQUIRE(run(std::string(LAYERIZE_BIN) + " " + dir + "/card.exr --iscolorspace srgb_tx"
                    + " --focus 3 -o " + dir + "/layers.exr",
                log) == 0);
    const ImageBuf layers = read_image(dir + "/layers.exr");
    REQUIRE(layers.initialized());
    float p[5];
    layers.getpixel(8, 4, p);
    CHECK(p[0] == Approx(0.2140).epsilon(1e-3));  // sRGB 0.5 decoded
    CHECK(p[3] == Approx(1.0f));
}

TEST_CASE("layerize reports bad input like defocus")
{
    const std::string dir = scratch_dir("cli_layerize_errors");
    const std::string layerize = LAYERIZE_BIN;
    std::string log;
    CHECK(run(layerize + " " + dir + "/missing.exr --focus 3 -o " + dir + "/o.exr", log) != 0);
    CHECK(one_line_naming(log, "missing.exr: no such file"));
    CHECK(run(layerize + " " + example_scene() + " --focus 3", log) != 0);
    CHECK(one_line_naming(log, "-o OUTPUT.exr or --info"));
    CHECK(run(layerize + " " + example_scene() + camera + " -o " + dir + "/o.png", log) != 0);
    CHECK(one_line_naming(log, "o.png"));
    CHECK_FALSE(Filesystem::exists(dir + "/o.png"));
}

TEST_CASE("colour: the config used is reported, and $OCIO is obeyed")
{
    const std::string dir = scratch_dir("cli_colour_config");
    std::string log;
    REQUIRE(run_defocus(example_scene() + " -o " + dir + "/a.exr" + camera + " -v", log) == 0);
    CHECK(Strutil::contains(log, "share/defocus/config.ocio (shipped)"));
    REQUIRE(run("OCIO=" + std::string(SHIPPED_OCIO_CONFIG) + " " + DEFOCUS_BIN + " "
                    + example_scene() + " -o " + dir + "/b.exr" + camera + " -v",
                log) == 0);
    CHECK(Strutil::contains(log, "($OCIO)"));
}

TEST_CASE("colour: bad preview displays and views are one-line errors, and nothing is written")
{
    const std::string dir = scratch_dir("cli_colour_errors");
    const std::string out = dir + "/out.exr";
    struct Case {
        std::string args, mentions;
    };
    const std::vector<Case> cases = {
        { " --preview " + dir + "/p.png --display Projector", "displays: sRGB" },
        { " --preview " + dir + "/p.png --display-view Film", "views: ACES 1.0 - SDR Video, Raw" },
    };
    for (const Case& c : cases) {
        INFO(c.args);
        std::string log;
        CHECK(run_defocus(example_scene() + " -o " + out + camera + c.args, log) == 1);
        CHECK(one_line_naming(log, c.mentions));
        CHECK_FALSE(Filesystem::exists(out));
        CHECK_FALSE(Filesystem::exists(dir + "/p.png"));
    }
}

TEST_CASE("colour: --preview writes an 8-bit image, and says once that the input space is a guess")
{
    // What the preview holds is the library's (test_color); here, the files.
    const std::string dir = scratch_dir("cli_preview");
    std::string log;
    REQUIRE(run_defocus(example_scene() + " -o " + dir + "/out.exr" + camera + " --preview "
                            + dir + "/preview.png",
                        log) == 0);
    const ImageSpec preview_spec = read_spec(dir + "/preview.png");
    CHECK(preview_spec.format == TypeUInt8);
    CHECK(preview_spec.width == 320);
    CHECK(preview_spec.height == 180);
    CHECK(preview_spec.nchannels == 3);
    // Tagged as the display encoding it holds, and read back so: not as the
    // linear space the frame was in.
    CHECK_FALSE(Strutil::icontains(preview_spec.get_string_attribute("oiio:ColorSpace"), "linear"));
    CHECK(preview_spec.get_string_attribute("colorInteropID").empty());
    write_uniform_image(dir + "/z.exr", { "Z" }, { 4.0f }, 320, 180);
    std::string again;
    REQUIRE(run_defocus(dir + "/preview.png --depth " + dir + "/z.exr -o " + dir
                            + "/again.exr" + camera + " -v",
                        again) == 0);
    CHECK(Strutil::contains(again, "input 'sRGB - "));
    // An 8-bit input's type does not fit OpenEXR: -v names the half written.
    CHECK(Strutil::contains(again, "data window, half)"));
    // OIIO tags the EXR input with its generic "Linear", taken as linear
    // Rec.709: a guess, said once.
    CHECK(count_of(log, "input colour space 'Linear Rec.709 (sRGB)' is a guess") == 1);
    std::string named;
    REQUIRE(run_defocus(example_scene() + " -o " + dir + "/named.exr" + camera
                            + " --iscolorspace lin_rec709 --preview " + dir + "/named.png"
                            + " --preview-alpha",
                        named) == 0);
    CHECK_FALSE(Strutil::contains(named, "guess"));
    CHECK(read_spec(dir + "/named.png").nchannels == 4);
    std::string sequence;
    REQUIRE(run_defocus(example_scene() + " --frames 1-3 -o " + dir + "/seq.#.exr" + camera
                            + " -v --preview " + dir + "/seq.#.png",
                        sequence) == 0);
    CHECK(count_of(sequence, "warning: ") == 1);
    CHECK(count_of(sequence, "(a guess: the file's generic 'Linear' tag") == 3);  // -v
}

TEST_CASE("colour: any format OIIO writes, e.g. an sRGB JPEG proxy")
{
    const std::string dir = scratch_dir("cli_proxy");
    std::string log;
    REQUIRE(run_defocus(example_scene() + " -o " + dir + "/proxy.jpg" + camera
                            + " --iscolorspace lin_rec709 --tocolorspace srgb_tx",
                        log) == 0);
    const ImageBuf proxy = read_image(dir + "/proxy.jpg");
    REQUIRE(proxy.initialized());
    const ImageSpec proxy_spec = read_spec(dir + "/proxy.jpg");
    CHECK(proxy_spec.format == TypeUInt8);
    CHECK(proxy_spec.width == 320);  // the display window
    CHECK(proxy_spec.nchannels == 3);
    // The same render as linear EXR, encoded by hand, matches the JPEG.
    REQUIRE(run_defocus(example_scene() + " -o " + dir + "/linear.exr -d float" + camera
                            + " --iscolorspace lin_rec709",
                        log) == 0);
    const ImageBuf linear = read_image(dir + "/linear.exr");
    REQUIRE(linear.initialized());
    float a[4], b[3];
    linear.getpixel(100, 150, a);
    proxy.getpixel(100, 150, b);
    for (int c = 0; c < 3; ++c) {
        const float v = a[c] / a[3];
        const float encoded = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1 / 2.4f) - 0.055f;
        CHECK(b[c] == Approx(std::clamp(encoded * a[3], 0.0f, 1.0f)).margin(4.0 / 255));
    }
}

namespace {

/// The option names a text lists: at a line's start for --help, in the
/// first column of a table for the manual.
std::set<std::string> option_names(const std::string& text, const std::string& before)
{
    std::set<std::string> names;
    const std::regex option("^" + before + "(-{1,2}[a-z][-a-z]*)");
    for (const std::string& line : Strutil::splits(text, "\n")) {
        std::smatch m;
        if (std::regex_search(line, m, option))
            names.insert(m[1]);
    }
    return names;
}

/// A flat RGBA+Z scene, 20x20: opaque, the left half at 2 m, the right
/// half at 6 m.
float attribute(const std::string& file, const char* name)
{
    const ImageSpec spec = read_spec(file);
    REQUIRE(spec.width > 0);
    const ParamValue* value = spec.find_attribute(name);
    if (!value)
        return -1.0f;
    return value->type() == TypeInt ? float(value->get_int()) : value->get_float();
}

}  // namespace

TEST_CASE("a chunk's log begins with the version, host, date and its frames")
{
    const std::string dir = scratch_dir("cli_chunk_log");
    std::string log;
    REQUIRE(run_defocus(two_depth_scene(dir) + " -o " + dir + "/c.#.exr --frames 1-5 --focus 3 "
                        "--chunk 2/2",
                        log) == 0);
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    CHECK_THAT(log, Catch::StartsWith(format("defocus {} on {} at ", defocus::version(), host)));
    CHECK_THAT(Strutil::splits(log, "\n")[0], Catch::EndsWith(" UTC: chunk 2/2, frames 3-5"));
}

TEST_CASE("on a terminal, the progress bar clears to a one-line summary")
{
    // script(1) gives the command a terminal, so it draws its bar.
    const std::string dir = scratch_dir("cli_terminal");
    const std::string scene = two_depth_scene(dir);
    std::string log;
    REQUIRE(run(format("script -qec '{} {} -o {}/one.exr --focus 3' /dev/null", defocus_bin,
                       scene, dir),
                log) == 0);
    CHECK_THAT(log, Catch::Contains("\rwrote " + dir + "/one.exr in "));
    CHECK_THAT(log, Catch::EndsWith(" s\r\n"));
    REQUIRE(run(format("script -qec '{} {} -o {}/seq.#.exr --frames 1-3 --focus 3' /dev/null",
                       defocus_bin, scene, dir),
                log) == 0);
    CHECK_THAT(log, Catch::Contains("\rwrote 3 of 3 frames in "));
}

TEST_CASE("sequences: frame patterns in and out, progress lines, errors")
{
    const std::string dir = scratch_dir("cli_sequence");
    for (int f : { 1001, 1002, 1003 })
        REQUIRE(Filesystem::copy(example_scene(), format("{}/in.{}.exr", dir, f)));
    std::string log;
    REQUIRE(run_defocus(dir + "/in.#.exr -o " + dir + "/out.#.exr --focal 50 --fstop 1001:2,1003:4"
                            + " --focus 1001:1,1003:4 --frames 1001-1003",
                        log) == 0);
    // Plain lines when stdout is not a terminal, and a summary.
    CHECK(std::regex_search(log, std::regex("frame 1002 \\([123]/3\\): wrote .*/out.1002.exr in ")));
    CHECK(Strutil::contains(log, "defocus: 3 of 3 frames written"));
    CHECK(attribute(dir + "/out.1002.exr", "defocus:focusDistance") == Approx(1.6f));

    // The input's own frames by default; '@' and %0Nd patterns; -q is silent.
    REQUIRE(run_defocus(dir + "/in.%04d.exr -o " + dir + "/b.@@@@.exr" + camera + " -q", log) == 0);
    CHECK(log.empty());
    for (int f : { 1001, 1002, 1003 })
        CHECK(Filesystem::exists(format("{}/b.{}.exr", dir, f)));
    // Several frames into one file name would overwrite each other.
    REQUIRE(run_defocus(dir + "/in.#.exr -o " + dir + "/one.exr" + camera, log) == 1);
    CHECK(one_line_naming(log, "3 frames need a frame pattern"));
    // A still with keyframes needs frames.
    REQUIRE(run_defocus(example_scene() + " -o " + dir + "/s.exr --focus 1:1,3:4", log) == 1);
    CHECK(one_line_naming(log, "give --frames"));
    // One still rendered over frames: a focus pull.
    REQUIRE(run_defocus(example_scene() + " --frames 1-2 -o " + dir + "/pull.#.exr --focus 1:1,2:4",
                        log) == 0);
    CHECK(attribute(dir + "/pull.0002.exr", "defocus:focusDistance") == 4.0f);
}

TEST_CASE("a bad frame is named, the others are written, the exit is non-zero")
{
    const std::string dir = scratch_dir("cli_bad_frame");
    for (int f : { 1, 2, 3, 4 })
        REQUIRE(Filesystem::copy(example_scene(), format("{}/in.{:04}.exr", dir, f)));
    Filesystem::write_text_file(dir + "/in.0003.exr", "not an EXR");
    std::string log;
    REQUIRE(run_defocus(dir + "/in.#.exr -o " + dir + "/out.#.exr" + camera + " -q", log) == 1);
    CHECK(Strutil::contains(log, "defocus: frame 3: " + dir + "/in.0003.exr"));
    CHECK(Strutil::contains(log, "defocus: 3 of 4 frames written; failed: 3\n"));
    for (int f : { 1, 2, 4 })
        CHECK(Filesystem::exists(format("{}/out.{:04}.exr", dir, f)));
    CHECK_FALSE(Filesystem::exists(dir + "/out.0003.exr"));

    // --stop-on-error: nothing starts after the bad frame. The first frame
    // runs alone, so a bad first frame stops everything.
    Filesystem::write_text_file(dir + "/in.0001.exr", "not an EXR");
    REQUIRE(run_defocus(dir + "/in.#.exr -o " + dir + "/stop.#.exr" + camera
                            + " -q --stop-on-error",
                        log) == 1);
    CHECK(Strutil::contains(log, "0 of 4 frames written; failed: 1; stopped at the first bad frame"));
    CHECK_FALSE(Filesystem::exists(dir + "/stop.0002.exr"));
}

TEST_CASE(".dof scene files: saved, rendered, overridden by flags, errors in one line")
{
    const std::string dir = scratch_dir("cli_dof");
    std::string log;
    const std::string settings = " --focal 50 --fstop 1.8 --focus 4 --aperture polygon --blades 5";
    REQUIRE(run_defocus(example_scene() + settings + " -o " + dir + "/direct.exr", log) == 0);
    // Without -o, --save-scene only saves.
    REQUIRE(run_defocus(example_scene() + settings + " --save-scene " + dir + "/shot.dof", log) == 0);
    CHECK(Strutil::contains(log, "wrote " + dir + "/shot.dof"));
    REQUIRE(run_defocus(dir + "/shot.dof -o " + dir + "/from_dof.exr", log) == 0);
    const ImageBuf direct = read_image(dir + "/direct.exr"),
                   from_dof = read_image(dir + "/from_dof.exr");
    CHECK(ImageBufAlgo::compare(direct, from_dof, 0.0f, 0.0f).nfail == 0);

    // Flags override the file's values.
    REQUIRE(run_defocus(dir + "/shot.dof -o " + dir + "/f4.exr --fstop 4", log) == 0);
    CHECK(attribute(dir + "/f4.exr", "defocus:fNumber") == 4.0f);
    CHECK(attribute(dir + "/f4.exr", "defocus:blades") == 5.0f);

    Filesystem::write_text_file(dir + "/broken.dof", "{\"version\": 1,");
    REQUIRE(run_defocus(dir + "/broken.dof -o " + dir + "/x.exr", log) == 1);
    CHECK(one_line_naming(log, "broken.dof: not valid JSON"));
    Filesystem::write_text_file(dir + "/missing.dof", "{\"version\": 1, \"inputs\": [\"gone.exr\"]}");
    REQUIRE(run_defocus(dir + "/missing.dof -o " + dir + "/x.exr", log) == 1);
    CHECK(one_line_naming(log, "gone.exr: no such file"));
    REQUIRE(run_defocus(dir + "/shot.dof " + example_scene() + " -o " + dir + "/x.exr", log) == 1);
    CHECK(one_line_naming(log, "must be the only input"));
    CHECK_FALSE(Filesystem::exists(dir + "/x.exr"));
}

// The manual's settings reference is generated from the table; the guide's
// table explains the options in more words, and must name none that the
// tool does not take.
TEST_CASE("the manual's option table names only options the help lists")
{
    std::string help, guide;
    REQUIRE(run_defocus("--help", help) == 0);
    REQUIRE(Filesystem::read_text_file(COMMAND_LINE_GUIDE, guide));
    const size_t table = guide.find("## Options");
    REQUIRE(table != std::string::npos);
    const std::set<std::string> in_help = option_names(help, "\\s+");
    const std::set<std::string> in_guide = option_names(guide.substr(table), "\\| `");
    CHECK(in_guide.size() > 30);
    for (const std::string& name : in_guide)
        CHECK(in_help.count(name) == 1);
    CHECK(Strutil::contains(help, "Examples:"));
}

TEST_CASE("a frame list of billions, a device or a pipe as input: one-line errors, no hang")
{
    const std::string dir = scratch_dir("cli_hostile");
    const std::string scene = two_depth_scene(dir);
    std::string log;
    // Enumerating 2e9 frames took gigabytes and ended in bad_alloc.
    REQUIRE(run_defocus(scene + " -o " + dir + "/o.#.exr --focus 3 --frames 1-2000000000", log)
            == 1);
    CHECK(one_line_naming(log, "names 2000000000 frames; a shot renders at most 1000000"));
    // OpenImageIO read "1001-11001040:2" as 11 million frames (fuzz_settings:
    // a timeout): what is not one of the documented forms is refused.
    REQUIRE(run_defocus(scene + " -o " + dir + "/o.#.exr --focus 3 --frames 1001-11001040:2", log)
            == 1);
    CHECK(one_line_naming(log, "'1001-11001040:2' is not a frame list"));
    REQUIRE(run_defocus(scene + " -o " + dir + "/o.#.exr --focus 3 --frames 1-2000000y1", log)
            == 1);
    CHECK(one_line_naming(log, "'1-2000000y1' names no frames"));
    // The format probe read /dev/zero and a FIFO forever.
    const std::string fifo = dir + "/pipe.exr";
    REQUIRE(mkfifo(fifo.c_str(), 0600) == 0);
    for (const std::string& input : { std::string("/dev/zero"), fifo }) {
        REQUIRE(run_defocus(input + " -o " + dir + "/p.exr --focus 3", log) == 1);
        CHECK(one_line_naming(log, input + ": not a regular file"));
    }
    REQUIRE(run_defocus(scene + " -o " + dir + "/p.exr --focus 3 --aperture mask:/dev/zero", log)
            == 1);
    CHECK(one_line_naming(log, "/dev/zero"));
    CHECK(Strutil::contains(log, "not a regular file"));
    CHECK_FALSE(Filesystem::exists(dir + "/p.exr"));
}

namespace {

/// Starts defocus with `args` (output to /dev/null); its process id.
pid_t start_defocus(const std::vector<std::string>& args,
                    const std::string& stderr_file = "/dev/null")
{
    std::vector<std::string> all = { defocus_bin };
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : all)
        argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 2, stderr_file.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    pid_t pid = -1;
    const int failed = posix_spawn(&pid, defocus_bin.c_str(), &actions, nullptr, argv.data(),
                                   environ);
    posix_spawn_file_actions_destroy(&actions);
    REQUIRE(failed == 0);
    return pid;
}

/// Runs defocus with `args` to the end, its errors to `stderr_file`; its
/// exit code (-1 when a signal ended it) and its peak resident memory in KB.
struct Finished {
    int exit_code;
    double peak_kb;
};
Finished run_to_end(const std::vector<std::string>& args,
                    const std::string& stderr_file = "/dev/null")
{
    const pid_t pid = start_defocus(args, stderr_file);
    int status = 0;
    struct rusage usage = {};
    REQUIRE(wait4(pid, &status, 0, &usage) == pid);
    return { WIFEXITED(status) ? WEXITSTATUS(status) : -1, double(usage.ru_maxrss) };
}

/// The names of the files in a folder, sorted.
std::vector<std::string> folder(const std::string& dir)
{
    std::vector<std::string> entries, names;
    Filesystem::get_directory_entries(dir, entries);
    for (const std::string& e : entries)
        names.push_back(Filesystem::filename(e));
    std::sort(names.begin(), names.end());
    return names;
}

}  // namespace

TEST_CASE("an output that is not a regular file, or not ours to write, is never replaced")
{
    const std::string dir = scratch_dir("cli_not_regular");
    std::string log;
    // A FIFO stays a FIFO.
    const std::string fifo = dir + "/fifo.exr";
    REQUIRE(::mkfifo(fifo.c_str(), 0644) == 0);
    CHECK(run_defocus(example_scene() + " -o " + fifo + camera, log) != 0);
    CHECK(one_line_naming(log, "fifo.exr: is a FIFO, not a regular file: not replaced"));
    struct stat after;
    REQUIRE(::stat(fifo.c_str(), &after) == 0);
    CHECK(S_ISFIFO(after.st_mode));
    // A file replaced keeps its mode and owner.
    const std::string kept = dir + "/kept.exr";
    Filesystem::write_text_file(kept, "old");
    REQUIRE(::chmod(kept.c_str(), 0640) == 0);
    REQUIRE(run_defocus(example_scene() + " -o " + kept + camera, log) == 0);
    REQUIRE(::stat(kept.c_str(), &after) == 0);
    CHECK((after.st_mode & 07777) == 0640);
    CHECK(after.st_size > 3);
    // A read-only file that this user cannot write is refused, as cp would:
    // run as nobody in a folder anyone may write. The checkout may lie in
    // a folder nobody cannot enter (mktemp -d makes them 0700), so the
    // program and the scene are copied into one under /tmp.
    if (geteuid() == 0) {
        const std::string shared = "/tmp/defocus-test-not-ours-" + std::to_string(getpid());
        Filesystem::remove_all(shared);
        REQUIRE(Filesystem::create_directory(shared));
        REQUIRE(::chmod(shared.c_str(), 01777) == 0);
        const std::string program = shared + "/defocus", scene = shared + "/scene.exr";
        REQUIRE(Filesystem::copy(DEFOCUS_BIN, program));
        REQUIRE(Filesystem::copy(example_scene(), scene));
        REQUIRE(::chmod(program.c_str(), 0755) == 0);
        REQUIRE(::chmod(scene.c_str(), 0644) == 0);
        const std::string locked = shared + "/locked.exr";
        Filesystem::write_text_file(locked, "old");
        REQUIRE(::chmod(locked.c_str(), 0444) == 0);
        const int status = run(format("setpriv --reuid=65534 --regid=65534 --clear-groups {} {} -o "
                                      "{}{}",
                                      program, scene, locked, camera),
                               log);
        CHECK(status != 0);
        CHECK(one_line_naming(log, "locked.exr: is read-only for you: not replaced"));
        std::string text;
        REQUIRE(Filesystem::read_text_file(locked, text));
        CHECK(text == "old");
        Filesystem::remove_all(shared);
    }
}

TEST_CASE("an interrupted run leaves its targets as they were and no temporary file")
{
    const std::string dir = scratch_dir("cli_interrupt");
    std::string log;
    REQUIRE(run(std::string(MAKE_EXAMPLE_SCENE_BIN) + " " + dir + "/scene.exr --width 960 "
                "--height 540", log) == 0);
    const std::string scene = dir + "/scene.exr", target = dir + "/o.exr";
    REQUIRE(run_defocus(scene + " -o " + target + " --focus 4", log) == 0);
    std::string before;
    REQUIRE(Filesystem::read_text_file(target, before));
    // --spread exact with --cateye spreads pixel by pixel, here with blurs
    // up to 200 px: some 2.5 s of work to interrupt at 0.4 s.
    const std::vector<std::string> slow = { "--focus", "4", "--focal", "85", "--fstop", "1",
                                            "--cateye", "1", "--spread", "exact" };
    const std::string errors = scratch_dir("cli_interrupt_log") + "/stderr.txt";
    auto slow_run = [&](std::vector<std::string> args) {
        args.insert(args.end(), slow.begin(), slow.end());
        return start_defocus(args, errors);
    };
    // A closed terminal and a reader gone from a pipe end a run as Ctrl-C
    // does: they used to leave the temporary file behind.
    for (const int signal_number : { SIGINT, SIGTERM, SIGHUP, SIGPIPE }) {
        INFO("signal " << signal_number);
        const pid_t pid = slow_run({ scene, "-o", target });
        usleep(400000);
        REQUIRE(kill(pid, signal_number) == 0);
        int status = 0;
        REQUIRE(waitpid(pid, &status, 0) == pid);
        CHECK(WIFSIGNALED(status));
        CHECK(WTERMSIG(status) == signal_number);  // a shell sees 128 + it
        CHECK(folder(dir) == std::vector<std::string> { "o.exr", "scene.exr" });
        std::string after;
        REQUIRE(Filesystem::read_text_file(target, after));
        CHECK(after == before);
    }
    // In a sequence, the frames written before the signal stay. Its frames
    // are quick ones: 40 take seconds, and the signal comes at the first.
    const pid_t pid = start_defocus({ scene, "-o", dir + "/s.#.exr", "--frames", "1-40",
                                      "--focus", "4" },
                                    errors);
    // Up to 2 minutes: a sanitized build is many times slower.
    for (int wait = 0; wait < 2400 && !Filesystem::exists(dir + "/s.0001.exr"); ++wait)
        usleep(50000);
    REQUIRE(kill(pid, SIGTERM) == 0);
    int status = 0;
    REQUIRE(waitpid(pid, &status, 0) == pid);
    CHECK(WIFSIGNALED(status));
    // The log (a farm task's) ends saying why.
    std::string said;
    REQUIRE(Filesystem::read_text_file(errors, said));
    CHECK_THAT(said, Catch::EndsWith("defocus: stopped by signal TERM: outputs not finished were "
                                     "not written\n"));
    for (const std::string& name : folder(dir))
        CHECK(name.find(".tmp") == std::string::npos);
    CHECK(read_image(dir + "/s.0001.exr").spec().width == read_spec(scene).width);  // complete
    // SIGKILL cannot be caught: what a killed process left is removed by
    // the next write of the same target on this host, and only that.
    const pid_t gone = fork();
    if (gone == 0)
        _exit(0);
    waitpid(gone, &status, 0);
    const std::string leftover = format("{}/.o.exr.{}.{}.tmp.exr", dir, this_host(), gone);
    const std::string running = format("{}/.o.exr.{}.{}.tmp.exr", dir, this_host(), getpid());
    Filesystem::write_text_file(leftover, "half a file");
    Filesystem::write_text_file(running, "another process's file in progress");
    REQUIRE(run_defocus(scene + " -o " + target + " --focus 4", log) == 0);
    CHECK_FALSE(Filesystem::exists(leftover));
    CHECK(Filesystem::exists(running));
}

TEST_CASE("an error about a .dof key holding a newline or a megabyte stays one short line")
{
    const std::string dir = scratch_dir("cli_error_line");
    const std::string scene = two_depth_scene(dir);
    Filesystem::write_text_file(dir + "/newline.dof",
                                "{\"version\": 1, \"inputs\": [\"two_depths.exr\"], "
                                "\"camera\": {\"fo\\ncus\": 3}}");
    Filesystem::write_text_file(dir + "/huge.dof",
                                "{\"version\": 1, \"inputs\": [\"two_depths.exr\"], \"camera\": {\""
                                    + std::string(1 << 20, 'k') + "\": 3}}");
    std::string log;
    REQUIRE(run_defocus(dir + "/newline.dof -o " + dir + "/o.exr", log) == 1);
    CHECK(one_line_naming(log, "unknown key 'camera.fo\\ncus'"));
    REQUIRE(run_defocus(dir + "/huge.dof -o " + dir + "/o.exr", log) == 1);
    CHECK(one_line_naming(log, "huge.dof"));
    CHECK(log.size() < 1100);
}

TEST_CASE("hostile .dof files: deep nesting, 100 MB, and inputs that are loops, folders or devices")
{
    const std::string dir = scratch_dir("cli_hostile_dof");
    const std::string scene = two_depth_scene(dir);
    auto dof = [&](const std::string& name, const std::string& inputs) {
        Filesystem::write_text_file(dir + "/" + name, "{\"version\": 1, \"inputs\": [" + inputs
                                                          + "], \"camera\": {\"focus\": 3}}");
        return dir + "/" + name;
    };
    const std::string nested = dof("nested.dof", std::string(100000, '[') + std::string(100000, ']'));
    std::string big_text = "{\"version\": 1, \"inputs\": [\"" + std::string(100 << 20, 'x') + "\"]}";
    Filesystem::write_text_file(dir + "/big.dof", big_text);
    big_text = std::string();
    Filesystem::remove(dir + "/loop_a.exr");
    Filesystem::remove(dir + "/loop_b.exr");
    REQUIRE(symlink("loop_b.exr", (dir + "/loop_a.exr").c_str()) == 0);
    REQUIRE(symlink("loop_a.exr", (dir + "/loop_b.exr").c_str()) == 0);
    Filesystem::create_directory(dir + "/folder.exr");
    const std::pair<std::string, std::string> cases[] = {
        { nested, "nested.dof: arrays and objects nested more than 32 deep: not a scene file" },
        { dir + "/big.dof", "big.dof: 100 MB is too large for a .dof scene file (at most 64 MB)" },
        { dof("loop.dof", "\"loop_a.exr\""), "loop.dof: inputs:" },
        { dof("folder.dof", "\"folder.exr\""), "folder.exr: is a directory, not an image" },
        { dof("zero.dof", "\"/dev/zero\""), "/dev/zero: not a regular file" },
    };
    for (const auto& [file, message] : cases) {
        INFO(file);
        std::string log;
        CHECK(run_defocus(file + " -o " + dir + "/o.exr", log) == 1);
        CHECK(one_line_naming(log, message));
        CHECK_FALSE(Filesystem::exists(dir + "/o.exr"));
    }
}

TEST_CASE("a symbolic link loop among a pattern's frames fails that frame alone")
{
    const std::string dir = scratch_dir("cli_pattern_loop");
    const std::string scene = two_depth_scene(dir);
    for (const char* frame : { "/f.0001.exr", "/f.0002.exr", "/f.0004.exr" })
        REQUIRE(Filesystem::copy(scene, dir + frame));
    // A loop as frame 3, and another entry of the folder that loops.
    REQUIRE(symlink("f.0003.exr", (dir + "/f.0003.exr").c_str()) == 0);
    REQUIRE(symlink("a_loop", (dir + "/a_loop").c_str()) == 0);
    std::string log;
    CHECK(run_defocus(dir + "/f.#.exr -o " + dir + "/o.#.exr --focus 3", log) == 1);
    CHECK(Strutil::contains(log, "3 of 4 frames written; failed: 3"));
    CHECK(Strutil::contains(log, "f.0003.exr: no such file"));
    for (const char* written : { "/o.0001.exr", "/o.0002.exr", "/o.0004.exr" })
        CHECK(Filesystem::exists(dir + written));
    CHECK_FALSE(Filesystem::exists(dir + "/o.0003.exr"));
}

TEST_CASE("a full disk: a one-line error, no partial file, the old output and other frames kept")
{
    const std::string dir = scratch_dir("cli_disk_full");
    std::string log;
    const std::string small = two_depth_scene(dir);
    REQUIRE(run(std::string(MAKE_EXAMPLE_SCENE_BIN) + " " + dir + "/big.exr --width 960 "
                    "--height 540", log) == 0);
    // A 16 KB disk: the 20x20 frame fits, the 960x540 one (2 MB as EXR,
    // 100s of KB as PNG or JPEG) does not. A tmpfs of that size is mounted
    // in a user and mount namespace of the test's own, which needs no
    // privilege; where those are not allowed, a file size limit of 16 KB
    // (ulimit -f) fails the same writes.
    const bool namespaces = run("unshare -rm true", log) == 0;
    if (!namespaces)
        WARN("no user namespaces here: a file size limit stands in for a full disk");
    const std::string disk = dir + "/disk";
    Filesystem::create_directory(disk);
    const std::string script = Strutil::fmt::format(R"(
        set -u
        cd '{dir}'
        {mount}
        D='{defocus}'
        $D small.exr -o disk/old.exr --focus 3 -q || echo "setup failed"
        $D small.exr -o disk/old.sgi --focus 3 -q || echo "setup failed"
        $D small.exr --focus 3 --save-scene disk/shot.dof -q || echo "setup failed"
        cp disk/old.exr old_copy.exr
        cp disk/old.sgi old_copy.sgi
        cp disk/shot.dof shot_copy.dof
        trap '' XFSZ
        {limit}
        for out in old.exr new.png new.jpg old.sgi new.tif; do
            $D big.exr -o disk/$out --focus 3 -q 2>err.txt; echo "$out exit $?"; cat err.txt
        done
        $D big.exr -o disk/preview.exr --preview disk/preview.png --focus 3 -q 2>err.txt
        echo "preview exit $?"; cat err.txt
        cmp -s disk/old.exr old_copy.exr && echo "old output intact"
        cmp -s disk/old.sgi old_copy.sgi && echo "old SGI intact"
        rm -f disk/preview.exr
        {fill}
        $D small.exr --focus 3 --fstop 2 --save-scene disk/shot.dof -q 2>err.txt
        echo "scene exit $?"; cat err.txt
        cmp -s disk/shot.dof shot_copy.dof && echo "old scene intact"
        rm -f disk/fill
        $D 'f.#.exr' -o 'disk/seq.#.exr' --focus 3 -q 2>err.txt; echo "sequence exit $?"
        cat err.txt
        ls -a disk | tr '\n' ' '; echo
    )",
        fmt::arg("dir", dir), fmt::arg("defocus", defocus_bin),
        fmt::arg("mount", namespaces ? "mount -t tmpfs -o size=16k tmpfs disk || exit 1" : ""),
        fmt::arg("limit", namespaces ? "" : "ulimit -f 16"),
        // A full disk for a small text file; past a size limit it fits.
        fmt::arg("fill", namespaces ? "cat big.exr > disk/fill 2>/dev/null" : ""));
    REQUIRE(Filesystem::copy(small, dir + "/small.exr"));
    REQUIRE(Filesystem::copy(small, dir + "/f.0001.exr"));
    REQUIRE(Filesystem::copy(dir + "/big.exr", dir + "/f.0002.exr"));
    Filesystem::write_text_file(dir + "/full.sh", script);
    const int status = run((namespaces ? "unshare -rm bash " : "bash ") + dir + "/full.sh", log);
    INFO(log);
    REQUIRE(status == 0);
    CHECK_FALSE(Strutil::contains(log, "setup failed"));
    // Each format says why.
    const std::string why = namespaces ? ": cannot write: No space left on device"
                                       : ": cannot write: File too large";
    for (const char* out : { "old.exr", "new.png", "new.jpg", "old.sgi", "new.tif" }) {
        CHECK(Strutil::contains(log, std::string(out) + " exit 1\ndefocus: disk/" + out + why));
    }
    CHECK(Strutil::contains(log, "preview exit 1\ndefocus: disk/preview.png" + why));
    CHECK(Strutil::contains(log, "old output intact"));
    CHECK(Strutil::contains(log, "old SGI intact"));
    if (namespaces) {
        // The scene file used to be truncated to nothing, with exit 0.
        CHECK(Strutil::contains(log, "scene exit 1\ndefocus: disk/shot.dof: cannot write"));
        CHECK(Strutil::contains(log, "old scene intact"));
    }
    CHECK(Strutil::contains(log, "sequence exit 1\n"));
    CHECK(Strutil::contains(log, "1 of 2 frames written; failed: 2"));
    // Nothing half-written: the old output, frame 1, and no temporary.
    CHECK(Strutil::contains(log, ". .. old.exr old.sgi seq.0001.exr shot.dof \n"));
}

TEST_CASE("two processes writing one output leave one complete file, never a mix")
{
    const std::string dir = scratch_dir("cli_two_writers");
    std::string log;
    REQUIRE(run(std::string(MAKE_EXAMPLE_SCENE_BIN) + " " + dir + "/scene.exr --width 640 "
                "--height 360", log) == 0);
    const std::string scene = dir + "/scene.exr";
    REQUIRE(run_defocus(scene + " -o " + dir + "/near.exr --focus 1 --compression none", log) == 0);
    REQUIRE(run_defocus(scene + " -o " + dir + "/far.exr --focus 8 --compression none", log) == 0);
    std::string near, far;
    REQUIRE(Filesystem::read_text_file(dir + "/near.exr", near));
    REQUIRE(Filesystem::read_text_file(dir + "/far.exr", far));
    for (int round = 0; round < 3; ++round) {
        const pid_t a = start_defocus({ scene, "-o", dir + "/both.exr", "--focus", "1",
                                        "--compression", "none" });
        const pid_t b = start_defocus({ scene, "-o", dir + "/both.exr", "--focus", "8",
                                        "--compression", "none" });
        int status_a = 0, status_b = 0;
        REQUIRE(waitpid(a, &status_a, 0) == a);
        REQUIRE(waitpid(b, &status_b, 0) == b);
        CHECK((WIFEXITED(status_a) && WEXITSTATUS(status_a) == 0));
        CHECK((WIFEXITED(status_b) && WEXITSTATUS(status_b) == 0));
        std::string both;
        REQUIRE(Filesystem::read_text_file(dir + "/both.exr", both));
        // Byte for byte one of the two (the metadata is the same but for
        // the focus).
        CHECK((both == near || both == far));
    }
    for (const std::string& name : folder(dir))
        CHECK(name.find(".tmp") == std::string::npos);
}

TEST_CASE("an input overwritten while it is read: a clean error or a correct result")
{
    const std::string dir = scratch_dir("cli_rewritten_input");
    std::string log;
    REQUIRE(run(std::string(MAKE_EXAMPLE_SCENE_BIN) + " " + dir + "/scene.exr --width 640 "
                "--height 360", log) == 0);
    REQUIRE(run_defocus(dir + "/scene.exr -o " + dir + "/expected.exr --focus 4", log) == 0);
    const ImageBuf expected = read_image(dir + "/expected.exr");
    // Another process rewrites the input in place (truncating it, then
    // writing it again in pieces) as fast as it can, while defocus reads it.
    const std::string script = Strutil::fmt::format(R"(
        while [ ! -e '{dir}/stop' ]; do
            head -c 20000 '{dir}/scene.exr' > '{dir}/live.exr'
            cat '{dir}/scene.exr' > '{dir}/live.exr'
        done)", fmt::arg("dir", dir));
    Filesystem::write_text_file(dir + "/rewrite.sh", script);
    const pid_t writer = fork();
    if (writer == 0) {
        execl("/bin/bash", "bash", (dir + "/rewrite.sh").c_str(), nullptr);
        _exit(127);
    }
    int correct = 0, refused = 0;
    for (int i = 0; i < 20; ++i) {
        const std::string out = format("{}/out{}.exr", dir, i);
        const int status = run_defocus(dir + "/live.exr -o " + out + " --focus 4", log);
        INFO(log);
        REQUIRE((status == 0 || status == 1));  // never a crash
        if (status == 1) {
            CHECK(one_line_naming(log, "live.exr"));
            CHECK_FALSE(Filesystem::exists(out));
            ++refused;
        } else if (ImageBufAlgo::compare(read_image(out), expected, 0.0f, 0.0f).maxerror == 0.0) {
            ++correct;
        } else {
            // Read between the rewrites' pieces, and whole: the same pixels.
            FAIL_CHECK("a run read a mix and wrote it: " << log);
        }
    }
    Filesystem::write_text_file(dir + "/stop", "");
    int status = 0;
    waitpid(writer, &status, 0);
    CHECK(correct + refused == 20);
}

TEST_CASE("a '%' in a frame pattern's name is a character of it, not a format")
{
    // Found by fuzz_settings: OpenImageIO formats the whole pattern, and
    // "a%s.#.exr" ended the process.
    const std::string dir = scratch_dir("cli_percent_pattern");
    const std::string scene = two_depth_scene(dir);
    for (const char* frame : { "/a%s.0001.exr", "/a%s.0002.exr" })
        REQUIRE(Filesystem::copy(scene, dir + frame));
    std::string log;
    REQUIRE(run_defocus("'" + dir + "/a%s.#.exr' -o '" + dir + "/o%x.#.exr' --focus 3", log)
            == 0);
    CHECK(Strutil::contains(log, "2 of 2 frames written"));
    CHECK(Filesystem::exists(dir + "/o%x.0002.exr"));
    REQUIRE(run_defocus("'" + dir + "/b%n.#.exr' -o '" + dir + "/o.#.exr' --focus 3 --frames 1",
                        log)
            == 1);
    CHECK(Strutil::contains(log, "b%n.0001.exr: no such file"));
}

TEST_CASE("memory over a 16-frame sequence stays bounded by the frames in flight", "[scale]")
{
    const std::string dir = scratch_dir("cli_sequence_memory");
    std::string log;
    REQUIRE(run(std::string(MAKE_EXAMPLE_SCENE_BIN) + " " + dir + "/f.0001.exr --width 1280 "
                "--height 720", log) == 0);
    for (int frame = 2; frame <= 16; ++frame)
        REQUIRE(Filesystem::copy(dir + "/f.0001.exr", format("{}/f.{:04d}.exr", dir, frame)));
    const Finished first = run_to_end({ dir + "/f.0001.exr", "-o", dir + "/one.exr", "--focus",
                                        "4" });
    // Two frames at most run side by side here (--threads 2): with the
    // program's own memory, under twice one frame's peak, however long the
    // sequence.
    const Finished all = run_to_end({ dir + "/f.#.exr", "-o", dir + "/o.#.exr", "--focus", "4",
                                      "--threads", "2" });
    REQUIRE(first.exit_code == 0);
    REQUIRE(all.exit_code == 0);
    const double one = first.peak_kb, sixteen = all.peak_kb;
    INFO("one frame " << one / 1024 << " MB, 16 frames " << sixteen / 1024 << " MB");
    CHECK(sixteen < 2.0 * one);
    CHECK(Filesystem::exists(dir + "/o.0016.exr"));
}

TEST_CASE("a sequence whose later frames are larger stays within --memory-limit", "[scale]")
{
    // A small first frame made the scheduler expect every frame to be as
    // small, and run two of the large ones at once past the limit.
    const std::string dir = scratch_dir("cli_sequence_growing");
    std::string log;
    REQUIRE(run(format("{} {}/f.0001.exr --width 320 --height 180", MAKE_EXAMPLE_SCENE_BIN, dir),
                log) == 0);
    REQUIRE(run(format("{} {}/f.0002.exr --width 2880 --height 1620", MAKE_EXAMPLE_SCENE_BIN, dir),
                log) == 0);
    for (int frame = 3; frame <= 4; ++frame)
        REQUIRE(Filesystem::copy(dir + "/f.0002.exr", format("{}/f.{:04d}.exr", dir, frame)));
    const Finished large = run_to_end({ dir + "/f.0002.exr", "-o", dir + "/one.exr", "--focus",
                                        "4", "--threads", "2" });
    // One large frame fits in the limit, two do not. What one asks for,
    // with the program's own memory, is 1.32 times its peak: the estimate
    // counts the aperture cells' buffers as if every tile took them (1.22
    // with --aperture-cells 1).
    const std::string limit = format("{}M", int(large.peak_kb / 1024 * 1.4));
    const Finished all = run_to_end({ dir + "/f.#.exr", "-o", dir + "/o.#.exr", "--focus", "4",
                                      "--threads", "2", "--memory-limit", limit });
    REQUIRE(large.exit_code == 0);
    REQUIRE(all.exit_code == 0);
    INFO("one large frame " << large.peak_kb / 1024 << " MB, the sequence " << all.peak_kb / 1024
                            << " MB, limit " << limit);
    CHECK(all.peak_kb < 1.5 * large.peak_kb);
    CHECK(Filesystem::exists(dir + "/o.0004.exr"));
}

/// Bars 4 px wide, every 24 px, in `parts` layers from 1 m to 1.5 m, each
/// shifted 3 px from the last, before a striped wall at 20 m: a layered
/// EXR of width × height that takes aperture cells over all of it.
std::string fence_parts(const std::string& dir, int width, int height, int parts)
{
    const std::string path = dir + "/fence.exr";
    std::vector<ImageSpec> specs(size_t(parts) + 1, rgbaz_spec(width, height));
    auto out = ImageOutput::create(path);
    for (size_t p = 0; p < specs.size(); ++p)
        specs[p].attribute("name", format("layer{}", p));
    REQUIRE(out->open(path, int(specs.size()), specs.data()));
    for (size_t p = 0; p < specs.size(); ++p) {
        ImageBuf image(specs[p]);
        const float depth = p == 0 ? 20.0f : 1.0f + 0.5f * float(p - 1) / float(parts);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const bool wall = p == 0, bar = (x + 3 * int(p)) % 24 < 4;
                const float shade = wall ? ((x / 5) % 2 ? 1.0f : 0.1f) : 0.02f;
                const float rgbaz[5] = { shade, shade, shade, 1.0f, depth };
                const float none[5] = { 0, 0, 0, 0, depth };
                image.setpixel(x, y, wall || bar ? rgbaz : none);
            }
        REQUIRE((p == 0 || out->open(path, specs[p], ImageOutput::AppendSubimage)));
        REQUIRE(out->write_image(TypeFloat, image.localpixels()));
    }
    REQUIRE(out->close());
    return path;
}

TEST_CASE("the memory limit bounds the peak memory of a render's process", "[scale]")
{
    // A flat 4K frame peaked at 775 MB under --memory-limit 700M: the
    // estimate left out the rebuilt plane, each layer's blur field and
    // highlight mask, and the program itself (120 MB of code and
    // libraries). Nor did it count what compositing per cell of the
    // aperture holds: each layer's changes, the layers as the cells read
    // them and each thread's bands. Rendered under the least limit its
    // refusals ask for, the process stays within it: a flat frame, and
    // fences in many layers with automatic cells, also under axial
    // aberration (red and blue take cells of their own).
    const std::string dir = scratch_dir("cli_memory_limit_flat");
    std::string log;
    REQUIRE(run(format("{} {}/layers.exr --width 1920 --height 1080", MAKE_EXAMPLE_SCENE_BIN,
                       dir),
                log) == 0);
    const std::string flat = dir + "/flat.exr";
    flatten_example(dir + "/layers.exr", flat);
    const std::string fence = fence_parts(dir, 960, 540, 6);
    // "... needs N MB, more than the L MB the memory limit of M MB ...":
    // the limit it asks for is M + N - L (M + N - M without the program).
    const std::regex refusal("needs ([0-9.]+) MB, more than the (?:([0-9.]+) (MB|bytes) the )?"
                             "memory limit of ([0-9.]+) MB");
    for (const auto& [input, cells, axial] : { std::tuple(flat, "1", "0"),
                                               std::tuple(fence, "0", "0"),
                                               std::tuple(fence, "0", "0.3") }) {
        double limit_mb = 64.0;
        Finished rendered { -1, 0.0 };
        for (int attempt = 0; attempt < 6 && rendered.exit_code != 0; ++attempt) {
            const std::string limit = format("{}M", int(std::ceil(limit_mb)));
            rendered = run_to_end({ input, "-o", dir + "/o.exr", "--focal", "50", "--fstop",
                                    "1.8", "--focus", "4", "--aperture-cells", cells,
                                    "--axial-ca", axial, "--memory-limit", limit },
                                  dir + "/said.txt");
            if (rendered.exit_code == 0)
                break;
            std::string said;
            REQUIRE(Filesystem::read_text_file(dir + "/said.txt", said));
            said = std::regex_replace(said, std::regex("\\s+"), " ");  // as one line
            std::smatch m;
            INFO(said);
            REQUIRE(std::regex_search(said, m, refusal));
            const double need = std::stod(m[1]), given = std::stod(m[4]);
            const double left = !m[2].matched ? given : m[3] == "MB" ? std::stod(m[2]) : 0.0;
            limit_mb = given + need - left + 1.0;
        }
        INFO(input << ", --aperture-cells " << cells << " --axial-ca " << axial << ": limit "
                   << limit_mb << " MB, peak " << rendered.peak_kb / 1024 << " MB");
        REQUIRE(rendered.exit_code == 0);
        if (under_address_sanitizer) {
            WARN("peak not checked: AddressSanitizer's shadow memory is in it");
            continue;
        }
        CHECK(rendered.peak_kb / 1024 <= limit_mb);
    }
}

TEST_CASE("a strip a pixel high under a wide blur is not extended into gigabytes")
{
    // --edge auto repeated its row 257 times up and down: 7.6 GB, 20 s.
    const std::string dir = scratch_dir("cli_strip");
    write_uniform_image(dir + "/strip.exr", { "R", "G", "B", "A", "Z" }, { 1, 1, 1, 1, 2 }, 400000,
                        1, TypeHalf);
    // A layer alone takes no aperture cells: nothing in front of it hides
    // anything, and its memory estimate counts none.
    for (const char* cells : { "1", "0" }) {
        const Finished run = run_to_end({ dir + "/strip.exr", "-o", dir + "/o.exr", "--focus",
                                          "3", "--aperture-cells", cells });
        INFO("--aperture-cells " << cells << ": peak " << run.peak_kb / 1024 << " MB");
        CHECK(run.exit_code == 0);
        CHECK(run.peak_kb < 1024 * 1024);
    }
    CHECK(no_nan(read_image(dir + "/o.exr")));
}

TEST_CASE("files the fuzzers found are refused quickly and cheaply")
{
    const std::string dir = scratch_dir("cli_fuzz_found");
    struct Found {
        const char* file;
        const char* message;
    };
    // fuzz_scene: a 4 KB EXR whose 'type' attribute declares 1.8 GB, which
    // OpenEXR's C++ interface allocated before finding the file short
    // (4 s, 1.9 GB; over 10 s under ASan).
    // fuzz_scene: a header giving 'channels', 'compression' and
    // 'dataWindow' twice; OpenImageIO's reader took one of each, OpenEXR's
    // core library the other, and decoded past the buffers (a crash).
    // fuzz_scene: a deep part 738 million pixels wide, whose chunk's table
    // of sample counts OpenEXR's C++ reader sizes in an int: it asked for
    // a negative size (bad_alloc; under ASan, an abort).
    // fuzz_read: a 417-byte EXR whose rows are 100 million pixels wide:
    // OpenEXR's C++ interface allocated a buffer of one chunk per thread
    // to open it (3.2 GB; 10 s under ASan).
    const Found found[] = {
        { "found_huge_attribute.exr",
          "attribute 'type' declares 1828716552 bytes, past the end of the file" },
        { "found_attribute_twice.exr", "attribute 'channels' is given twice in one header" },
        { "found_deep_chunk_too_wide.exr",
          "part 0's deep chunks hold 738197512 pixels each, more than OpenEXR can count" },
        { "found_wide_rows.exr", "decoding one chunk needs 1.49 GB, more than" },
    };
    for (const Found& f : found) {
        INFO(f.file);
        const Finished run
            = run_to_end({ std::string(FUZZ_CORPUS_DIR) + "/scene/" + f.file, "-o",
                           dir + "/o.exr", "--focus", "2", "--memory-limit", "1G" });
        CHECK(run.exit_code == 1);
        CHECK(run.peak_kb < 1024 * 1024);  // under 1 GB
        std::string log;
        run_defocus(std::string(FUZZ_CORPUS_DIR) + "/scene/" + f.file + " -o " + dir
                        + "/o.exr --focus 2 --memory-limit 1G",
                    log);
        CHECK(one_line_naming(log, f.message));
    }
    // fuzz_scene: deep samples of alpha up to 7.7e31 composited into NaN.
    std::string log;
    REQUIRE(run_defocus(std::string(FUZZ_CORPUS_DIR) + "/scene/found_deep_alpha.exr -o " + dir
                            + "/deep.exr --focus 2 --max-blur 6 -v",
                        log)
            == 0);
    CHECK(Strutil::contains(log, "11 with alpha above 1 clamped to 1"));
    CHECK(no_nan(read_image(dir + "/deep.exr")));
    // fuzz_read: an output in the way whose damaged header OpenImageIO's
    // reader allocated gigabytes for (untouched pages here, a finding under
    // the sanitizers: 10 s) when --skip-existing looked for its settings
    // hash: OpenEXR's core library reads it now, and it is rendered over.
    REQUIRE(run(std::string(MAKE_EXAMPLE_SCENE_BIN) + " " + dir + "/scene.exr --width 64 "
                "--height 36", log) == 0);
    for (const char* file : { "found_tile_description_oom.exr", "found_slow_header.exr" }) {
        INFO(file);
        Filesystem::remove(dir + "/in_the_way.exr");
        REQUIRE(Filesystem::copy(std::string(FUZZ_CORPUS_DIR) + "/read/" + file,
                                 dir + "/in_the_way.exr"));
        const Finished run = run_to_end({ dir + "/scene.exr", "-o", dir + "/in_the_way.exr",
                                          "--focus", "2", "--skip-existing" });
        CHECK(run.exit_code == 0);
        CHECK(run.peak_kb < 512 * 1024);
        CHECK(read_image(dir + "/in_the_way.exr").spec().full_width == 64);
    }
}
