// Real data from ../shared/data: fidelity on the path-traced garden scene
// (scored with the metric in its README), the OpenEXR project's deep,
// stereo and multi-part images, and its corpus of damaged files. Skips
// when the data is absent.
#define CATCH_CONFIG_EXTERNAL_INTERFACES  // listeners
#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>

#include <defocus/color/color.h>
#include <defocus/io/scene_io.h>
#include <defocus/optics/camera.h>

#include "region_split.h"
#include "test_support.h"

using namespace defocus_test;
using OIIO::ImageBuf;
using OIIO::Strutil::fmt::format;

namespace {

const int skip_status = 77;  // CTest's SKIP_RETURN_CODE for this test

std::string garden_folder()
{
    return shared_data() + "/scenes/garden";
}

std::string garden(const std::string& file)
{
    return garden_folder() + "/" + file;
}

std::string openexr(const std::string& file)
{
    return shared_data() + "/openexr-images/" + file;
}

ImageBuf read_float(const std::string& file)
{
    ImageBuf image = read_image(file);
    INFO(file);
    REQUIRE(image.initialized());
    return image;
}

/// Runs a tool (DEFOCUS_BIN or LAYERIZE_BIN) and requires success.
void run_ok(const std::string& tool, const std::string& args)
{
    std::string log;
    INFO(tool << " " << args << "\n" << log);
    const int status = run(tool + " " + args, log);
    INFO(log);
    REQUIRE(status == 0);
}

const std::string garden_camera = " --focal 85 --fstop 1.4";

// deep.exr lacks the anti-aliased rims of some lights: Blender gives a
// pixel the light covers in part the empty depth 1e10, so merging the
// layers dropped that sample behind the far wall. The light in focus at
// (678, 182) alone costs deep.exr 3.4 of its 111 units of squared error at
// focus 1.25 where flat.exr, which has its rim, loses 0.5. Up to this many
// dB, deep may score below its flattening.
const double rimless_lights = 0.1;

/// Defocuses `input` (extra defocus flags allowed) into `out` with
/// garden's camera at a focus distance.
void render_garden(const std::string& input, const std::string& out, double focus,
                   const std::string& aperture)
{
    run_ok(DEFOCUS_BIN, format("{} -o {}{} --focus {} --aperture {} -q", input, out,
                               garden_camera, focus, aperture));
}

/// PSNR of a render against the truth at its focus distance; `offset`
/// places the truth's display window in the result (Blender's file has no
/// overscan window).
double truth_psnr(const std::string& render, double focus, int offset)
{
    const std::string truth = focus == 3.0 ? "truth_focus3.exr" : "truth_focus1.25.exr";
    return garden_psnr(read_float(render), read_float(garden(truth)), offset, offset);
}

/// The render of one of garden's files (extra flags allowed): several
/// tests score the same ones, and each is made once.
std::string rendered(const std::string& input, double focus, const std::string& aperture)
{
    static const std::string dir = scratch_dir("garden_renders");
    static std::map<std::string, std::string> renders;
    const std::string key = format("{} {} {}", input, focus, aperture);
    if (const auto known = renders.find(key); known != renders.end())
        return known->second;
    const std::string out = format("{}/{}.exr", dir, renders.size());
    render_garden(input, out, focus, aperture);
    return renders[key] = out;
}

/// PSNR of `input` against the truth at a focus distance, with the box
/// aperture unless told otherwise.
double score(const std::string& input, double focus, int offset = 0,
             const std::string& aperture = "box")
{
    return truth_psnr(rendered(input, focus, aperture), focus, offset);
}

/// The same, through layerize's multi-part output fed back to defocus.
double score_via_layerize(const std::string& input, double focus, int offset = 0)
{
    const std::string dir = scratch_dir("garden_layerize");
    run_ok(LAYERIZE_BIN, format("{} -o {}/layers.exr --focal 85 --fstop 1.4 --focus {}", input,
                                dir, focus));
    render_garden(dir + "/layers.exr" + (offset ? " --sensor 43.2" : ""), dir + "/out.exr", focus,
                  "box");
    return truth_psnr(dir + "/out.exr", focus, offset);
}

bool finite_with_alpha_in_unit_range(const ImageBuf& image)
{
    const auto stats = OIIO::ImageBufAlgo::computePixelStats(image);
    for (size_t c = 0; c < stats.nancount.size(); ++c)
        if (stats.nancount[c] || stats.infcount[c])
            return false;
    return stats.min[3] >= 0.0f && stats.max[3] <= 1.0f + 1e-6f;
}

}  // namespace

TEST_CASE("box aperture on layers.exr scores against the path-traced truths", "[garden]")
{
    const double focus3 = score(garden("layers.exr"), 3.0);
    const double focus125 = score(garden("layers.exr"), 1.25);
    WARN("garden layers.exr, box: " << focus3 << " dB at focus 3, " << focus125
                                    << " dB at focus 1.25");
    CHECK(focus3 >= 33.9);
    CHECK(focus125 >= 35.9);
}

TEST_CASE("the disc aperture on layers.exr scores close to exact disc spreading", "[garden]")
{
    // The default, bounded-time disc merges large blurs in blocks; exact
    // scanline spreading is what it must stay close to. (Antialiased edges
    // given their object's depth, not the renderer's 1e10, gain 0.1 dB.)
    // Composited over the whole aperture at once (--aperture-cells 1), the
    // layers score 39.06 / 38.58: by default, per part of the lens
    // (sub-aperture compositing), the near objects hide what they hide
    // from each part.
    const double focus3 = score(garden("layers.exr"), 3.0, 0, "disc");
    const double focus125 = score(garden("layers.exr"), 1.25, 0, "disc");
    const double exact3 = score(garden("layers.exr") + " --spread exact", 3.0, 0, "disc");
    const double exact125 = score(garden("layers.exr") + " --spread exact", 1.25, 0, "disc");
    const double whole3 = score(garden("layers.exr") + " --aperture-cells 1", 3.0, 0, "disc");
    WARN("garden layers.exr, disc, automatic cells: " << focus3 << " / " << focus125
                                                      << " dB at focus 3 / 1.25; exact: "
                                                      << exact3 << " / " << exact125
                                                      << " dB; one cell at focus 3: " << whole3);
    CHECK(focus3 >= 44.0);
    CHECK(focus125 >= 41.0);
    CHECK(whole3 >= 39.0);
    CHECK(focus3 >= exact3 - 0.05);
    CHECK(focus125 >= exact125 - 0.05);
}

TEST_CASE("the hybrid method beats the box alone, taking few pixels the slow way", "[garden]")
{
    const std::string disc_psf = std::string(EXAMPLES_DIR) + "/psf/disc_rim.exr";
    for (double focus : { 3.0, 1.25 }) {
        const double box = score(garden("layers.exr"), focus);
        const std::string out = scratch_dir("hybrid") + "/out.exr";
        std::string log;
        REQUIRE(run(format("{} {} -o {}{} --focus {} --aperture box --psf-image {} -v", DEFOCUS_BIN,
                           garden("layers.exr"), out, garden_camera, focus, disc_psf),
                    log) == 0);
        const std::string truth = focus == 3.0 ? "truth_focus3.exr" : "truth_focus1.25.exr";
        const double hybrid = garden_psnr(read_float(out), read_float(garden(truth)));
        // "hybrid: N of M pixels (P%) spread with the PSF image"
        const size_t at = log.find("hybrid: ");
        REQUIRE(at != std::string::npos);
        const double percent = std::stod(log.substr(log.find('(', at) + 1));
        WARN("focus " << focus << ": box " << box << " dB, hybrid " << hybrid << " dB, "
                      << percent << "% of pixels the slow way");
        CHECK(hybrid > box + 0.5);
        CHECK(percent <= 5.0);
    }
}

TEST_CASE("the garden focus map at 3 m: the torus green, the pole red", "[garden]")
{
    const std::string out = scratch_dir("focusmap") + "/map.exr";
    run_ok(DEFOCUS_BIN, garden("layers.exr") + " -o " + out + garden_camera
                            + " --focus 3 --output focusmap -d float");
    const ImageBuf map = read_float(out);
    float torus[4], pole[4], wall[4];
    map.getpixel(620, 280, torus);  // the torus's right side
    map.getpixel(410, 100, pole);   // the pole, 1.2 m away
    map.getpixel(100, 300, wall);   // the far wall, 12 m away
    CHECK(torus[1] > 0.8f);
    CHECK(torus[1] > 4.0f * std::max(torus[0], torus[2]));
    CHECK(pole[0] > 0.5f);
    CHECK(pole[1] == 0.0f);
    CHECK(wall[2] > 0.5f);
    CHECK(wall[1] == 0.0f);
}

TEST_CASE("flat renders score above plain hard slicing, directly and through layerize", "[garden]")
{
    // Hard slicing into 8 layers uniform in 1/z reaches 29.3 and 27.5 dB;
    // flat.exr scored 33.55 and 33.75 dB before its mixed pixels were
    // split (a ghost bokeh disc at focus 1.25) and its layers followed the
    // occlusions.
    const std::string blender = garden("blender_multilayer.exr") + " --sensor 43.2";
    const double flat3 = score(garden("flat.exr"), 3.0);
    const double flat125 = score(garden("flat.exr"), 1.25);
    const double blender3 = score(blender, 3.0, 96);
    const double blender125 = score(blender, 1.25, 96);
    WARN("flat.exr: " << flat3 << " / " << flat125 << " dB; blender_multilayer.exr: "
                      << blender3 << " / " << blender125 << " dB");
    CHECK(flat3 >= 33.7);
    CHECK(flat125 >= 35.9);
    CHECK(blender3 >= 29.3);
    CHECK(blender125 >= 27.5);
    CHECK(score_via_layerize(garden("flat.exr"), 3.0) == Approx(flat3).margin(0.01));
    CHECK(score_via_layerize(garden("flat.exr"), 1.25) == Approx(flat125).margin(0.01));
    CHECK(score_via_layerize(garden("blender_multilayer.exr") + " --sensor 43.2", 1.25, 96)
          == Approx(blender125).margin(0.01));
}

TEST_CASE("deep.exr scores close to the layers and no lower than flat.exr", "[garden]")
{
    // deep.exr is occlusion-culled: the surfaces hidden behind opaque ones
    // are not in it, so its hidden background has to be filled like a flat
    // render's. That costs 0.2 dB against layers.exr at focus 3 here, and
    // nothing at 1.25 (0.8 and 2.4 dB while a light beside the pole flooded
    // the fill). Deep carries
    // exact coverage at edges: it must not do worse than its flattening,
    // but for the rims of lights it lacks (0.03 dB at focus 3 here).
    const double deep3 = score(garden("deep.exr"), 3.0);
    const double deep125 = score(garden("deep.exr"), 1.25);
    const double flat3 = score(garden("flat.exr"), 3.0);
    const double flat125 = score(garden("flat.exr"), 1.25);
    WARN("deep.exr: " << deep3 << " / " << deep125 << " dB; flat.exr: " << flat3 << " / "
                      << flat125 << " dB");
    CHECK(deep3 >= 33.6);
    CHECK(deep125 >= 35.8);
    CHECK(deep3 >= flat3 - rimless_lights);
    CHECK(deep125 >= flat125 - rimless_lights);
    CHECK(score_via_layerize(garden("deep.exr"), 3.0) == Approx(deep3).margin(0.01));
}

TEST_CASE("flat and deep input come close to the layers with the disc aperture", "[garden]")
{
    // flat.exr scored 37.83 / 35.05 dB before its mixed pixels were split
    // and its hidden surfaces rebuilt with structure, 38.27 / 38.03 dB
    // before the far surface was continued behind the near edge pixels, as
    // deep.exr holds it, and 38.46 / 38.58 (deep.exr 38.46 / 38.63)
    // composited over the whole aperture at once (--aperture-cells 1).
    const double flat3 = score(garden("flat.exr"), 3.0, 0, "disc");
    const double flat125 = score(garden("flat.exr"), 1.25, 0, "disc");
    const double deep3 = score(garden("deep.exr"), 3.0, 0, "disc");
    const double deep125 = score(garden("deep.exr"), 1.25, 0, "disc");
    WARN("disc: flat.exr " << flat3 << " / " << flat125 << " dB, deep.exr " << deep3 << " / "
                           << deep125 << " dB");
    CHECK(flat3 >= 40.3);
    CHECK(flat125 >= 41.2);
    CHECK(deep3 >= 40.3);
    CHECK(deep125 >= 41.2);
    CHECK(deep3 >= flat3 - rimless_lights);
    CHECK(deep125 >= flat125 - rimless_lights);
}

TEST_CASE("garden's error, split into what the pinhole view knows and what the lens reveals",
          "[garden]")
{
    // The revealed region receives light from surfaces nearer ones hide
    // from the pinhole view: flat and deep renders must rebuild them. The
    // split is ../shared/tools/known_region.py's, which gave the same
    // numbers to 0.01 dB when the layers were composited over the whole
    // aperture at once (layers 43.14 / 33.64 dB at focus 3, 43.88 / 35.56
    // at 1.25; flat 43.12 / 32.79, 43.85 / 35.57; deep 43.17 / 32.78,
    // 43.87 / 35.62). Per part of the lens the layers come close to the
    // truth's noise floor in both regions (46.09 / 43.78 and 43.00 /
    // 40.14), and what flat and deep lose there is their rebuild's alone
    // (flat 34.07 / 38.80 revealed): within 1 dB of the layers is issue
    // 63's bar, not met yet, so these bars only keep what the rebuild
    // reaches.
    using namespace defocus_fidelity;
    const std::string dir = scratch_dir("garden_split");
    for (const double focus : { 3.0, 1.25 }) {
        const std::string truth = focus == 3.0 ? "truth_focus3.exr" : "truth_focus1.25.exr";
        SceneSplit split;
        std::string error;
        const bool made = split_scene(
            garden_folder(), garden(truth), dir,
            [&](const std::string& input, const std::string& output) {
                std::error_code failed;
                std::filesystem::copy_file(rendered(input, focus, "disc"), output,
                                           std::filesystem::copy_options::overwrite_existing,
                                           failed);
                return !failed;
            },
            split, error);
        INFO(error);
        REQUIRE(made);
        const RegionPsnr &l = split.layers, &f = split.flat, &d = split.deep;
        WARN(format("focus {}: {:.1f}% revealed; known / revealed dB: layers {:.2f} / {:.2f}, "
                    "flat {:.2f} / {:.2f}, deep {:.2f} / {:.2f}",
                    focus, 100.0 * l.revealed_share, l.known, l.revealed, f.known, f.revealed,
                    d.known, d.revealed));
        CHECK(l.revealed_share > 0.1);
        CHECK(l.known >= (focus == 3.0 ? 45.5 : 42.5));
        CHECK(l.revealed >= (focus == 3.0 ? 43.2 : 39.6));
        for (const RegionPsnr& rebuilt : { f, d }) {
            CHECK(rebuilt.known >= l.known - 0.3);
            CHECK(rebuilt.revealed >= (focus == 3.0 ? 33.5 : 38.2));
        }
        CHECK(d.known >= f.known - rimless_lights);
        CHECK(d.revealed >= f.revealed - rimless_lights);
    }
}

TEST_CASE("automatic layering of flat.exr at f/4 comes close to the given layers", "[garden]")
{
    // At f/4 the whole blur range fits in one 24 px span of CoC: cut by
    // CoC alone, the blurred pole, the in-focus torus and the background
    // shared two layers (37.8 dB against the layered render). The cuts now
    // follow the occlusions.
    const std::string dir = scratch_dir("garden_f4");
    for (const char* input : { "flat", "layers" })
        run_ok(DEFOCUS_BIN, format("{} -o {}/{}.exr --focal 85 --fstop 4 --focus 3 --aperture disc",
                                   garden(std::string(input) + ".exr"), dir, input));
    const double psnr = garden_psnr(read_float(dir + "/flat.exr"), read_float(dir + "/layers.exr"));
    WARN("flat.exr against layers.exr at f/4, focus 3: " << psnr << " dB");
    CHECK(psnr >= 43.0);
}

TEST_CASE("garden's Z as 1/z, ray distance and CoC renders as the planar Z does", "[garden]")
{
    // flat.exr's Z rewritten three ways, as renderers and painted maps
    // write depth; the sky (Z 1e10) becomes 0, 1e10 and the limiting CoC.
    const std::string dir = scratch_dir("garden_depth_kinds");
    const ImageBuf flat = read_float(garden("flat.exr"));
    const OIIO::ImageSpec& spec = flat.spec();
    const int z_channel = spec.channelindex("Z");
    const double f = 0.085, fpx = 0.085 / 0.036 * 960, focus = 1.25;
    const double limit = f * fpx / 1.4;  // the CoC diameter of infinity
    auto write_kind = [&](const std::string& kind, auto&& value_of) {
        ImageBuf out(OIIO::ImageSpec(spec.width, spec.height, spec.nchannels, OIIO::TypeFloat));
        out.specmod().channelnames = spec.channelnames;
        out.specmod().full_width = spec.full_width;
        out.specmod().full_height = spec.full_height;
        out.set_origin(spec.x, spec.y);
        std::vector<float> pixel(spec.nchannels);
        for (OIIO::ImageBuf::Iterator<float> it(out); !it.done(); ++it) {
            flat.getpixel(it.x(), it.y(), pixel.data());
            const double z = pixel[z_channel], sky = z >= 1e9;
            const double u = (it.x() + 0.5 - 480) / fpx, v = (it.y() + 0.5 - 270) / fpx;
            pixel[z_channel] = float(value_of(z, sky, std::sqrt(1 + u * u + v * v)));
            for (int c = 0; c < spec.nchannels; ++c)
                it[c] = pixel[c];
        }
        REQUIRE(out.write(dir + "/" + kind + ".exr"));
    };
    write_kind("inverse", [](double z, bool sky, double) { return sky ? 0.0 : 1.0 / z; });
    write_kind("distance", [](double z, bool, double ray) { return z * ray; });
    write_kind("coc", [&](double z, bool sky, double) {
        return sky ? limit : f * fpx / 1.4 * (1 / focus - 1 / z);
    });
    const ImageBuf planar = read_float(rendered(garden("flat.exr"), focus, "disc"));
    for (const std::string kind : { "inverse", "distance", "coc" }) {
        const std::string camera
            = kind == "coc" ? "" : garden_camera + " --focus 1.25";
        run_ok(DEFOCUS_BIN, format("{}/{}.exr -o {}/{}_out.exr{} --depth-kind {} --aperture disc",
                                   dir, kind, dir, kind, camera, kind));
        const double psnr = garden_psnr(read_float(dir + "/" + kind + "_out.exr"), planar);
        WARN("--depth-kind " << kind << " against planar Z: " << psnr << " dB");
        CHECK(psnr >= 50.0);
    }
}

TEST_CASE("the layer view draws each layer -v lists in its own colour", "[garden]")
{
    const std::string out = scratch_dir("garden_layer_view") + "/layers.exr";
    std::string log;
    REQUIRE(run(format("{} {} -o {}{} --focus 3 --output layers -v", DEFOCUS_BIN,
                       garden("flat.exr"), out, garden_camera),
                log) == 0);
    INFO(log);
    std::vector<Imath::V3f> listed;
    for (size_t at = log.find(" drawn #"); at != std::string::npos;
         at = log.find(" drawn #", at + 1)) {
        const unsigned rgb = std::stoul(log.substr(at + 8, 6), nullptr, 16);
        listed.emplace_back((rgb >> 16) / 255.0f, ((rgb >> 8) & 255) / 255.0f,
                            (rgb & 255) / 255.0f);
    }
    REQUIRE(listed.size() >= 4);
    // Each pixel's nearest listed colour: every layer is the nearest of
    // some, and the background's fills most of the frame unmixed.
    const ImageBuf view = read_float(out);
    std::vector<int64_t> nearest(listed.size(), 0);
    int64_t exactly_background = 0;
    for (OIIO::ImageBuf::ConstIterator<float> it(view); !it.done(); ++it) {
        if (it[3] == 0.0f)
            continue;
        const Imath::V3f c(it[0], it[1], it[2]);
        size_t best = 0;
        for (size_t l = 1; l < listed.size(); ++l)
            if ((c - listed[l]).length2() < (c - listed[best]).length2())
                best = l;
        ++nearest[best];
        exactly_background += (c - listed[0]).length() < 0.003f;
    }
    for (size_t l = 0; l < listed.size(); ++l) {
        INFO("layer " << l << " is the nearest colour of " << nearest[l] << " pixels");
        CHECK(nearest[l] > 0);
    }
    CHECK(exactly_background > view.spec().image_pixels() / 4);
}

TEST_CASE("an sRGB-encoded render is spread in linear light", "[garden]")
{
    // An sRGB-encoded copy of flat.exr, made with the shipped config:
    // un-premultiplied, encoded, premultiplied again; Z untouched.
    defocus::ColorManagement colour;
    std::string error;
    REQUIRE(colour.load(SHIPPED_OCIO_CONFIG, error));
    ImageBuf flat = read_float(garden("flat.exr"));
    ImageBuf rgba = OIIO::ImageBufAlgo::channels(flat, 4, { 0, 1, 2, 3 });
    rgba.specmod().alpha_channel = 3;
    REQUIRE(colour.convert(rgba, "lin_rec709", "srgb_tx", error));
    ImageBuf encoded = OIIO::ImageBufAlgo::channel_append(
        rgba, OIIO::ImageBufAlgo::channels(flat, 1, { 4 }));
    encoded.specmod().channelnames = { "R", "G", "B", "A", "Z" };
    const std::string dir = scratch_dir("encoded");
    REQUIRE(encoded.write(dir + "/flat_srgb.exr"));

    for (double focus : { 3.0, 1.25 }) {
        // flat.exr as it is: an untagged EXR is read as scene-linear.
        const double linear = score(garden("flat.exr"), focus);
        const double managed = score(dir + "/flat_srgb.exr --iscolorspace srgb_tx --tocolorspace lin_rec709", focus);
        // Blurring the encoded values as if they were light, then decoding.
        const std::string naive_out = dir + "/naive.exr";
        run_ok(DEFOCUS_BIN, format("{}/flat_srgb.exr -o {}{} --focus {} --aperture box "
                                   "--iscolorspace lin_rec709",
                                   dir, naive_out, garden_camera, focus));
        ImageBuf naive = read_float(naive_out);
        REQUIRE(colour.convert(naive, "srgb_tx", "lin_rec709", error));
        const std::string truth = focus == 3.0 ? "truth_focus3.exr" : "truth_focus1.25.exr";
        const double blurred_encoded = garden_psnr(naive, read_float(garden(truth)));
        WARN("focus " << focus << ": linear input " << linear << " dB, sRGB input managed "
                      << managed << " dB, encoded values blurred " << blurred_encoded << " dB");
        CHECK(std::abs(managed - linear) <= 0.3);
        CHECK(blurred_encoded <= linear - 1.0);
    }
}

TEST_CASE("Weta's deep passes, alone and together, give sane images in depth order", "[openexr]")
{
    const std::string v = openexr("v2/LowResLeftView/");
    const std::vector<std::string> inputs = {
        v + "Balls.exr", v + "Leaves.exr", v + "Trunks.exr",
        v + "Trunks.exr " + v + "Leaves.exr " + v + "Balls.exr",
        // The full-size stereo file, by its right view (LowResLeftView
        // holds its left at half the size).
        openexr("v2/Stereo/Trunks.exr") + " --view right",
    };
    const size_t all_three = 3;  // the inputs' entry with all three passes
    const std::string dir = scratch_dir("weta");
    auto sharp_path = [&](size_t i) { return format("{}/sharp{}.exr", dir, i); };
    auto blur_path = [&](size_t i) { return format("{}/blur{}.exr", dir, i); };
    for (size_t i = 0; i < inputs.size(); ++i) {
        INFO(inputs[i]);
        // Nearly a pinhole: the result is the flattened deep image, so its
        // light and coverage are the input's.
        run_ok(DEFOCUS_BIN, inputs[i] + " -o " + sharp_path(i) + " --focal 500 --fstop 1000 --focus 200 -d float");
        // A long lens wide open: CoC from -9 to +21 px.
        run_ok(DEFOCUS_BIN, inputs[i] + " -o " + blur_path(i) + " --focal 500 --fstop 3 --focus 200 -d float");
        const ImageBuf sharp = read_float(sharp_path(i)), blur = read_float(blur_path(i));
        CHECK(finite_with_alpha_in_unit_range(sharp));
        CHECK(finite_with_alpha_in_unit_range(blur));
        // Spreading moves light and coverage, occlusion hides some: within 5%.
        for (int c = 0; c < 4; ++c)
            CHECK(channel_sum(blur, c) == Approx(channel_sum(sharp, c)).epsilon(0.05));
    }

    // Depth order, all three at once: where the front-most surface is in
    // focus and no blurred foreground is near, the result is the sharp image.
    defocus::Scene scene;
    std::string error;
    REQUIRE(defocus::read_scene({ v + "Trunks.exr", v + "Leaves.exr", v + "Balls.exr" }, {},
                                scene, error));
    const defocus::DeepImage& deep = scene.deep.front();
    defocus::Camera cam;
    cam.focal_length_mm = 500;
    cam.fstop = 3;
    cam.focus_distance = 200;
    const defocus::CircleOfConfusion coc(cam, scene.spec.roi_full());
    const ImageBuf sharp = read_float(sharp_path(all_three)), blur = read_float(blur_path(all_three));
    const OIIO::ROI roi = deep.roi;
    std::vector<float> front_coc(roi.npixels(), 0.0f);
    for (int64_t p = 0; p < roi.npixels(); ++p) {
        float z = INFINITY;
        for (uint64_t i = deep.offsets[p]; i < deep.offsets[p + 1]; ++i)
            if (deep.samples[i].a > 0.0f)
                z = std::min(z, deep.samples[i].z);
        front_coc[p] = std::isinf(z) ? NAN
                                     : float(coc.diameter(z, roi.xbegin + int(p % roi.width()),
                                                          roi.ybegin + int(p / roi.width())));
    }
    int64_t in_focus = 0;
    double diff = 0.0;
    const int reach = 25;  // beyond the largest blur radius
    for (int y = roi.ybegin + reach; y < roi.yend - reach; ++y)
        for (int x = roi.xbegin + reach; x < roi.xend - reach; ++x) {
            const float c = front_coc[deep.pixel_index(x, y)];
            if (!(std::abs(c) < 1.0f))
                continue;
            bool blurred_front_near = false;
            for (int j = -reach; j <= reach && !blurred_front_near; j += 3)
                for (int i = -reach; i <= reach && !blurred_front_near; i += 3) {
                    const float n = front_coc[deep.pixel_index(x + i, y + j)];
                    blurred_front_near = n < -1.0f && std::hypot(i, j) < 0.5 * -n + 2;
                }
            if (blurred_front_near)
                continue;
            float a[4], b[4];
            sharp.getpixel(x, y, a);
            blur.getpixel(x, y, b);
            if (a[3] < 0.99f)
                continue;
            ++in_focus;
            for (int k = 0; k < 3; ++k)
                diff += std::abs(a[k] - b[k]);
        }
    INFO(in_focus << " in-focus pixels");
    REQUIRE(in_focus > 1000);
    CHECK(diff / (3.0 * in_focus) < 0.01);
}

TEST_CASE("the Beachball stereo sequence's views defocus to sane images", "[openexr]")
{
    const std::string dir = scratch_dir("beachball");
    for (const char* view : { "left", "right" }) {
        INFO(view);
        const std::string out = dir + "/" + view + ".exr";
        run_ok(DEFOCUS_BIN, openexr("Beachball/multipart.0001.exr") + " --view " + view + " -o "
                                + out + " --focal 50 --fstop 2 --focus 5 -v");
        const ImageBuf image = read_float(out);
        CHECK(image.spec().full_width == 2048);
        CHECK(image.spec().full_height == 1556);
        CHECK(finite_with_alpha_in_unit_range(image));
        CHECK(channel_sum(image, 3) > 1000.0);
    }
}

TEST_CASE("the Beachball sequence: 8 frames of the left view, the input's windows", "[sequences]")
{
    const std::string dir = scratch_dir("beachball_sequence");
    std::string log;
    // As a user runs it, from the sequence's folder.
    REQUIRE(run(format("cd {} && {} multipart.#.exr --frames 1-8 --view left --focal 50 "
                       "--fstop 2 --focus 5 -o {}/out.#.exr",
                       openexr("Beachball"), DEFOCUS_BIN, dir),
                log) == 0);
    CHECK(OIIO::Strutil::contains(log, "8 of 8 frames written"));
    for (int frame = 1; frame <= 8; ++frame) {
        INFO("frame " << frame);
        defocus::Scene input;
        std::string error;
        REQUIRE(defocus::read_scene({ openexr(format("Beachball/multipart.{:04}.exr", frame)) },
                                    { "left", "" }, input, error));
        const ImageBuf image = read_float(format("{}/out.{:04}.exr", dir, frame));
        const OIIO::ImageSpec& spec = image.spec();
        CHECK(spec.full_width == input.spec.full_width);
        CHECK(spec.full_height == input.spec.full_height);
        CHECK(spec.roi() == OIIO::ROI(input.spec.x, input.spec.x + input.spec.width,
                                      input.spec.y, input.spec.y + input.spec.height, 0, 1, 0, 4));
        CHECK(finite_with_alpha_in_unit_range(image));
        CHECK(spec.get_int_attribute("defocus:frame") == frame);
    }
}

TEST_CASE("a damaged frame in the Beachball sequence: the 7 good frames are written", "[sequences]")
{
    const std::string dir = scratch_dir("beachball_bad_frame");
    std::vector<std::string> damaged;
    OIIO::Filesystem::get_directory_entries(openexr("Damaged"), damaged);
    REQUIRE(!damaged.empty());
    std::sort(damaged.begin(), damaged.end());
    for (int frame = 1; frame <= 8; ++frame) {
        const std::string source = frame == 5 ? damaged.front()
                                              : openexr(format("Beachball/multipart.{:04}.exr", frame));
        REQUIRE(symlink(source.c_str(), format("{}/multipart.{:04}.exr", dir, frame).c_str()) == 0);
    }
    std::string log;
    CHECK(run(format("{} {}/multipart.#.exr --frames 1-8 --view left --focal 50 --fstop 2 "
                     "--focus 5 -o {}/out.#.exr",
                     DEFOCUS_BIN, dir, dir),
              log) == 1);
    INFO(log);
    CHECK(OIIO::Strutil::contains(log, "defocus: frame 5: "));
    CHECK(OIIO::Strutil::contains(log, "defocus: 7 of 8 frames written; failed: 5\n"));
    for (int frame = 1; frame <= 8; ++frame)
        CHECK(OIIO::Filesystem::exists(format("{}/out.{:04}.exr", dir, frame)) == (frame != 5));
}

TEST_CASE("a focus pull over 24 frames changes the image smoothly, without popping", "[sequences]")
{
    // Focus from 1.25 m to 3 m, linear in 1/z: the CoC moves 2.8 px a frame.
    // flat.exr: each frame makes anew both choices that could pop, where
    // its layers are cut and which tiles take cells; given layers make
    // only the second, and would double the cost.
    const std::string dir = scratch_dir("focus_pull");
    run_ok(DEFOCUS_BIN, format("{} --frames 1-24 --focus 1:1.25,24:3.0{} -o {}/pull.#.exr -q",
                               garden("flat.exr"), garden_camera, dir));
    // RMS between consecutive frames in the garden metric's domain (sRGB,
    // clamped): what a viewer sees. In linear light a highlight 34 times
    // brighter than white dominates while it leaves focus.
    std::vector<double> steps;
    ImageBuf previous = read_float(dir + "/pull.0001.exr");
    for (int frame = 2; frame <= 24; ++frame) {
        ImageBuf current = read_float(format("{}/pull.{:04}.exr", dir, frame));
        steps.push_back(std::pow(10.0, -garden_psnr(current, previous) / 20.0));
        previous = std::move(current);
    }
    std::vector<double> sorted = steps;
    std::sort(sorted.begin(), sorted.end());
    const double median = sorted[sorted.size() / 2];
    const double largest = sorted.back();
    WARN("largest step " << largest / median << "x the median");
    CHECK(largest <= 2.0 * median);
    CHECK(sorted.front() > 0.0);  // every frame moved
}

TEST_CASE("every damaged file ends in a one-line error, quickly, with no output", "[damaged]")
{
    const std::string damaged = openexr("Damaged");
    std::vector<std::string> files;
    OIIO::Filesystem::get_directory_entries(damaged, files);
    REQUIRE(files.size() >= 180);
    std::sort(files.begin(), files.end());
    // Every file through the library in this process: reading and
    // rendering it fails with one line naming it, in under 10 s.
    for (const std::string& file : files) {
        INFO(file);
        defocus::FrameResult result;
        std::string error;
        const auto start = std::chrono::steady_clock::now();
        CHECK_FALSE(render_with(file, { { "focus", "3" } }, result, error));
        const double seconds
            = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        INFO(error);
        CHECK(seconds < 10.0);
        CHECK(error.find('\n') == std::string::npos);
        CHECK(OIIO::Strutil::contains(error, OIIO::Filesystem::filename(file)));
    }
    // A tenth of them through the command, which adds the exit status and
    // the output (a process each: all of them took 76 s, 205 s under the
    // sanitizers).
    const std::string out = scratch_dir("damaged") + "/out.exr";
    for (size_t i = 0; i < files.size(); i += 10) {
        INFO(files[i]);
        std::string log;
        const int status
            = run(format("timeout 10 {} '{}' -o {} --focus 3", DEFOCUS_BIN, files[i], out), log);
        INFO(log);
        CHECK(status == 1);  // not a crash (>128), not the timeout (124)
        CHECK(std::count(log.begin(), log.end(), '\n') == 1);
        CHECK(OIIO::Strutil::contains(log, OIIO::Filesystem::filename(files[i])));
        CHECK_FALSE(OIIO::Filesystem::exists(out));
    }
}

namespace {

/// CTest runs the test cases by group, a test each (tests/CMakeLists.txt
/// names the groups): a test case outside every group would never run.
bool every_test_case_in_a_group()
{
    const std::vector<std::string> groups = OIIO::Strutil::splits(SHARED_DATA_GROUPS, ",");
    for (const Catch::TestCase& test :
         Catch::getRegistryHub().getTestCaseRegistry().getAllTests()) {
        const std::vector<std::string>& tags = test.getTestCaseInfo().tags;
        if (std::find_first_of(tags.begin(), tags.end(), groups.begin(), groups.end())
            == tags.end()) {
            std::printf("test case \"%s\" has no group tag of %s\n", test.name.c_str(),
                        SHARED_DATA_GROUPS);
            return false;
        }
    }
    return true;
}

/// Before any test: every test case in a group, and a skip (CTest's
/// SKIP_RETURN_CODE, with the reason it matches) without the data.
struct GroupsAndData : Catch::TestEventListenerBase {
    using TestEventListenerBase::TestEventListenerBase;
    void testRunStarting(const Catch::TestRunInfo&) override
    {
        if (!every_test_case_in_a_group())
            std::exit(1);
        if (shared_data().empty()) {
            std::printf("SKIPPED: no shared data at %s (set DEFOCUS_SHARED_DATA)\n",
                        DEFOCUS_SHARED_DATA);
            std::exit(skip_status);
        }
    }
};

}  // namespace

CATCH_REGISTER_LISTENER(GroupsAndData)
