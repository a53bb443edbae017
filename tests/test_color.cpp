// Colour management: the shipped config, round trips, premultiplication.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <cstdlib>

#include <OpenColorIO/OpenColorIO.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>
#include <OpenImageIO/imagebufalgo.h>

#include <defocus/color/color.h>
#include <defocus/color/color_plan.h>
#include <defocus/color/primaries.h>
#include <defocus/frame_report.h>
#include <defocus/render_frame.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using OIIO::ImageBuf;
namespace OCIO = OCIO_NAMESPACE;
using OIIO::ImageSpec;
using OIIO::ROI;

namespace {

ColorManagement shipped()
{
    ColorManagement config;
    std::string error;
    INFO(error);
    REQUIRE(config.load(SHIPPED_OCIO_CONFIG, error));
    return config;
}

ImageBuf rgba_pixels(const std::vector<std::array<float, 4>>& pixels)
{
    ImageBuf image = zero_image(ROI(0, int(pixels.size()), 0, 1), 4);
    image.specmod().alpha_channel = 3;
    for (size_t i = 0; i < pixels.size(); ++i)
        image.setpixel(int(i), 0, pixels[i].data());
    return image;
}

}  // namespace

TEST_CASE("the shipped config has the spaces, roles and display the pipeline needs")
{
    const ColorManagement c = shipped();
    CHECK(c.scene_linear() == "ACEScg");
    for (const char* space : { "ACES2065-1", "ACEScg", "ACEScct", "Linear Rec.709 (sRGB)",
                               "sRGB - Texture", "Raw" })
        CHECK(c.find_space(space) == space);
    CHECK(c.find_space("lin_rec709") == "Linear Rec.709 (sRGB)");
    CHECK(c.find_space("srgb_tx") == "sRGB - Texture");
    for (const char* role : { "aces_interchange", "cie_xyz_d65_interchange", "scene_linear",
                              "data", "color_picking" })
        CHECK_FALSE(c.find_space(role).empty());
    CHECK(c.is_data("Raw"));
    CHECK(c.is_linear("ACEScg"));
    CHECK(c.is_linear("Linear Rec.709 (sRGB)"));
    CHECK_FALSE(c.is_linear("sRGB - Texture"));
    CHECK_FALSE(c.is_linear("ACEScct"));
    CHECK(c.default_display() == "sRGB");
    std::string why;
    CHECK(c.check_display_view("sRGB", "ACES 1.0 - SDR Video", why));
    CHECK(c.check_display_view("sRGB", "Raw", why));
    CHECK_FALSE(c.check_display_view("sRGB", "Film", why));
    CHECK_THAT(why, Catch::Contains("ACES 1.0 - SDR Video"));
    std::string error;
    CHECK(c.require_space("Rec.2020", error).empty());
    CHECK_THAT(error, Catch::Contains("ACEScct"));
}

TEST_CASE("every space goes to scene_linear and back")
{
    const ColorManagement c = shipped();
    for (const char* space : { "ACES2065-1", "ACEScg", "ACEScct", "Linear Rec.709 (sRGB)",
                               "sRGB - Texture" }) {
        INFO(space);
        // Values in [0, 1]: within 1e-5.
        ImageBuf unit = rgba_pixels({ { 0.0f, 0.0f, 0.0f, 1.0f }, { 0.18f, 0.5f, 0.9f, 1.0f },
                                      { 1.0f, 0.02f, 0.3f, 1.0f }, { 0.7f, 0.7f, 0.7f, 1.0f } });
        const ImageBuf original(unit);
        std::string error;
        REQUIRE(c.convert(unit, space, c.scene_linear(), error));
        REQUIRE(c.convert(unit, c.scene_linear(), space, error));
        CHECK(worst_relative_error(unit, original, 0.0, 1e-5) <= 1.0);
        // HDR values through the linear spaces: within 1e-4 relative, from
        // 1e-3 to 1e4. (A float 3x3 matrix cannot keep 1e-3 beside 1e4 in
        // one pixel to that bar; real HDR pixels are bright in all channels.)
        if (c.is_linear(space)) {
            ImageBuf hdr = rgba_pixels({ { 1e-3f, 2e-3f, 5e-3f, 1.0f }, { 12.0f, 30.0f, 7.0f, 1.0f },
                                         { 1e4f, 8e3f, 9e3f, 1.0f }, { 400.0f, 250.0f, 600.0f, 1.0f } });
            const ImageBuf hdr_original(hdr);
            REQUIRE(c.convert(hdr, space, c.scene_linear(), error));
            REQUIRE(c.convert(hdr, c.scene_linear(), space, error));
            CHECK(worst_relative_error(hdr, hdr_original, 1e-4, 0.0) <= 1.0);
        }
    }
}

TEST_CASE("conversions work on un-premultiplied colour and never touch alpha")
{
    const ColorManagement c = shipped();
    // A half-transparent pixel whose colour is sRGB-encoded 0.6, 0.3, 0.1.
    ImageBuf pixel = rgba_pixels({ { 0.3f, 0.15f, 0.05f, 0.5f } });
    std::string error;
    REQUIRE(c.convert(pixel, "srgb_tx", c.scene_linear(), error));
    float linear[4];
    pixel.getpixel(0, 0, linear);
    CHECK(linear[3] == 0.5f);
    // Premultiplied scene-linear: the decoded colour times alpha, where
    // decoding the premultiplied values would give a darker colour.
    ImageBuf decoded = rgba_pixels({ { 0.6f, 0.3f, 0.1f, 1.0f } });
    REQUIRE(c.convert(decoded, "srgb_tx", c.scene_linear(), error));
    float full[4];
    decoded.getpixel(0, 0, full);
    for (int i = 0; i < 3; ++i)
        CHECK(linear[i] == Approx(0.5f * full[i]).epsilon(1e-5));
    REQUIRE(c.convert(pixel, c.scene_linear(), "srgb_tx", error));
    float back[4];
    pixel.getpixel(0, 0, back);
    CHECK(back[0] / back[3] == Approx(0.6f).epsilon(1e-5));
    CHECK(back[1] / back[3] == Approx(0.3f).epsilon(1e-5));
    CHECK(back[2] / back[3] == Approx(0.1f).epsilon(1e-5));
    CHECK(back[3] == 0.5f);
}

TEST_CASE("the config comes from the argument, then $OCIO, then the shipped one")
{
    std::string error;
    ColorManagement from_file;
    REQUIRE(from_file.load(SHIPPED_OCIO_CONFIG, error));
    CHECK(command_line_words(from_file.origin()) == "--colorconfig");

    const std::string broken = scratch_dir("color_config") + "/broken.ocio";
    OIIO::Filesystem::write_text_file(broken, "ocio_profile_version: 2.1\nroles: [\n");
    setenv("OCIO", broken.c_str(), 1);
    ColorManagement from_env;
    CHECK_FALSE(from_env.load("", error));
    CHECK_THAT(error, Catch::Contains("broken.ocio") && Catch::Contains("$OCIO"));
    unsetenv("OCIO");

    ColorManagement default_config;
    REQUIRE(default_config.load("", error));
    CHECK(default_config.origin() == "shipped");
    CHECK_THAT(default_config.path(), Catch::Contains("share/defocus/config.ocio"));
}

TEST_CASE("luminance weights come from the config in use")
{
    CHECK(shipped().luma() == Imath::V3d(0.2126, 0.7152, 0.0722));
    // A config with other weights gives those.
    std::string text;
    REQUIRE(OIIO::Filesystem::read_text_file(SHIPPED_OCIO_CONFIG, text));
    REQUIRE(OIIO::Strutil::contains(text, "luma: [0.2126, 0.7152, 0.0722]"));
    const std::string other = scratch_dir("color_luma") + "/other_luma.ocio";
    OIIO::Filesystem::write_text_file(
        other, OIIO::Strutil::replace(text, "luma: [0.2126, 0.7152, 0.0722]",
                                      "luma: [0.25, 0.5, 0.25]"));
    ColorManagement config;
    std::string error;
    REQUIRE(config.load(other, error));
    CHECK(config.luma() == Imath::V3d(0.25, 0.5, 0.25));
    CHECK(luma_weights(&config) == config.luma());
    // Without a config the input is linear Rec.709.
    CHECK(luma_weights(nullptr) == Imath::V3d(0.2126, 0.7152, 0.0722));
}

TEST_CASE("an input's space comes from its colorInteropID, its tag, then its chromaticities")
{
    auto shared = std::make_shared<const ColorManagement>(shipped());
    auto plan_for = [&](const OIIO::ImageSpec& spec) {
        ColorPlan plan;
        std::string error;
        REQUIRE(plan_color(plan, shared, "", "", "", spec, error));
        return plan;
    };
    const struct {
        std::array<float, 8> xy;
        const char* space;
    } primaries[] = {
        { { 0.7347f, 0.2653f, 0.0f, 1.0f, 0.0001f, -0.077f, 0.32168f, 0.33767f }, "ACES2065-1" },
        { { 0.713f, 0.293f, 0.165f, 0.830f, 0.128f, 0.044f, 0.32168f, 0.33767f }, "ACEScg" },
        { { 0.64f, 0.33f, 0.30f, 0.60f, 0.15f, 0.06f, 0.3127f, 0.3290f }, "Linear Rec.709 (sRGB)" },
        { { 0.680f, 0.320f, 0.265f, 0.690f, 0.150f, 0.060f, 0.3127f, 0.3290f }, "Linear P3-D65" },
        { { 0.708f, 0.292f, 0.170f, 0.797f, 0.131f, 0.046f, 0.3127f, 0.3290f }, "Linear Rec.2020" },
    };
    for (const auto& p : primaries) {
        INFO(p.space);
        OIIO::ImageSpec spec(4, 4, 4, OIIO::TypeHalf);
        spec.attribute("oiio:ColorSpace", "Linear");  // as OIIO tags every EXR
        spec.attribute("chromaticities", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 8), p.xy.data());
        const ColorPlan plan = plan_for(spec);
        CHECK(plan.input == p.space);
        CHECK(plan.guess.empty());
        CHECK_THAT(plan.summary, Catch::Contains("from the file's chromaticities"));
        // What is written names the space again.
        OIIO::ImageSpec written(4, 4, 4, OIIO::TypeHalf);
        record_color_space(written, *shared, plan.input);
        CHECK(plan_for(written).input == p.space);
    }
    // The interop ID tells ACEScct from ACEScg, which share primaries.
    OIIO::ImageSpec cct(4, 4, 4, OIIO::TypeHalf);
    record_color_space(cct, *shared, "ACEScct");
    CHECK(cct.get_string_attribute("colorInteropID") == "acescct_ap1_scene");
    CHECK(plan_for(cct).input == "ACEScct");
    // Chromaticities nothing matches leave the old guess, said to be one.
    OIIO::ImageSpec odd(4, 4, 4, OIIO::TypeHalf);
    odd.attribute("oiio:ColorSpace", "Linear");
    const float xy[8] = { 0.6f, 0.3f, 0.3f, 0.6f, 0.1f, 0.1f, 0.3f, 0.3f };
    odd.attribute("chromaticities", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 8), xy);
    CHECK(plan_for(odd).input == "Linear Rec.709 (sRGB)");
    CHECK_FALSE(plan_for(odd).guess.empty());
    // A space files cannot name leaves no stale name behind.
    record_color_space(odd, *shared, "Raw");
    CHECK(odd.find_attribute("chromaticities") == nullptr);
}

TEST_CASE("P3-D65 and Rec.2020 convert to Rec.709 by the matrices of their primaries")
{
    // Rec.709 red, green and blue of pure P3 / Rec.2020 red: the first
    // column of inverse(M709) * M_P3 (both to XYZ with the D65 white).
    const ColorManagement c = shipped();
    const struct {
        const char* space;
        std::array<float, 3> red_in_rec709;
    } cases[] = { { "lin_p3d65", { 1.224940f, -0.042057f, -0.019638f } },
                  { "lin_rec2020", { 1.660491f, -0.124550f, -0.018151f } } };
    for (const auto& k : cases) {
        INFO(k.space);
        ImageBuf image = rgba_pixels({ { 1.0f, 0.0f, 0.0f, 1.0f } });
        std::string error;
        REQUIRE(c.convert(image, c.find_space(k.space), c.find_space("lin_rec709"), error));
        for (int ch = 0; ch < 3; ++ch)
            CHECK(image.getchannel(0, 0, 0, ch) == Approx(k.red_in_rec709[ch]).margin(2e-4));
    }
}

TEST_CASE("colour spaces and configs that cannot be used are one-line errors")
{
    const std::string dir = scratch_dir("color_errors");
    const std::string broken = dir + "/broken.ocio";
    OIIO::Filesystem::write_text_file(broken, "not: [a config\n");
    const std::vector<std::pair<Settings, std::string>> cases = {
        { { { "iscolorspace", "Rec.2020" } }, "spaces: CIE-XYZ-D65, sRGB - Display, ACES2065-1" },
        { { { "tocolorspace", "P3" } }, "unknown colour space 'P3'" },
        { { { "iscolorspace", "raw" } }, "'Raw' is data" },
        { { { "colorconfig", broken } }, "broken.ocio: colour config (--colorconfig) fails to load" },
        { { { "colorconfig", dir + "/gone.ocio" } },
          "gone.ocio: colour config (--colorconfig) not found" },
    };
    for (const auto& [settings, mentions] : cases) {
        INFO(settings.front().first << " " << settings.front().second);
        Settings all = settings;
        all.push_back({ "focus", "4" });
        FrameResult result;
        std::string error;
        CHECK_FALSE(render_with(example_scene(), all, result, error));
        CHECK(one_line_error(error, mentions));
    }
}

TEST_CASE("an $OCIO that names no usable config is an error, never colour left unmanaged")
{
    const std::string dir = scratch_dir("color_env");
    const std::string broken = dir + "/broken.ocio";
    OIIO::Filesystem::write_text_file(broken, "not: [a config\n");
    for (const std::string& env : { dir + "/gone.ocio", broken }) {
        INFO(env);
        setenv("OCIO", env.c_str(), 1);
        FrameResult result;
        std::string error;
        const bool rendered = render_with(example_scene(), { { "focus", "4" } }, result, error);
        unsetenv("OCIO");
        CHECK_FALSE(rendered);
        CHECK(one_line_error(error, env + ": colour config ($OCIO)"));
        CHECK_THAT(error, Catch::Contains("unset OCIO"));
    }
}

namespace {

/// A 20x20 RGBA+Z render in `dir` that names its colour space only by its
/// chromaticities, as renderers write them: orange at 2 m on the left, blue
/// at 6 m on the right.
std::string chromaticities_scene(const std::string& dir, const float* chromaticities)
{
    ImageSpec spec = rgbaz_spec(20, 20);
    spec.attribute("chromaticities", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 8), chromaticities);
    ImageBuf image(spec);
    OIIO::ImageBufAlgo::fill(image, { 0.9f, 0.3f, 0.1f, 1.0f, 2.0f });
    OIIO::ImageBufAlgo::fill(image, { 0.1f, 0.4f, 0.8f, 1.0f, 6.0f }, ROI(10, 20, 0, 20));
    const std::string path = dir + "/tagged.exr";
    REQUIRE(image.write(path));
    return path;
}

/// The chromaticities a header names, rounded to 1e-3 (empty: none).
std::vector<float> named_chromaticities(const ImageSpec& spec)
{
    const OIIO::ParamValue* p = spec.find_attribute("chromaticities");
    if (!p)
        return {};
    std::vector<float> values(8);
    std::copy_n(static_cast<const float*>(p->data()), 8, values.begin());
    for (float& v : values)
        v = std::round(v * 1000.0f) / 1000.0f;
    return values;
}

}  // namespace

TEST_CASE("a result names its space, and an input's named space is read back")
{
    const std::string dir = scratch_dir("color_names");
    const float ap1[8] = { 0.713f, 0.293f, 0.165f, 0.830f, 0.128f, 0.044f, 0.32168f, 0.33767f };
    const std::string scene = chromaticities_scene(dir, ap1);
    const Settings camera = { { "focal", "50" }, { "fstop", "1.8" }, { "focus", "4" } };
    auto with = [&](Settings more) {
        more.insert(more.begin(), camera.begin(), camera.end());
        return more;
    };
    FrameResult result;
    std::string error;

    // Read as ACEScg, from its chromaticities; the result says so.
    REQUIRE(render_with(scene, camera, result, error));
    CHECK_THAT(frame_report(result, shot_with({ scene }, camera), "once.exr"),
               Catch::Contains("input 'ACEScg' (from the file's chromaticities: ACES AP1)"));
    CHECK(named_chromaticities(result.image.spec())
          == std::vector<float> { 0.713f, 0.293f, 0.165f, 0.83f, 0.128f, 0.044f, 0.322f, 0.338f });
    CHECK(result.image.spec().get_string_attribute("colorInteropID") == "lin_ap1_scene");

    // Converted pixels never keep the input's chromaticities.
    REQUIRE(render_with(scene, with({ { "tocolorspace", "lin_rec709" } }), result, error));
    CHECK(named_chromaticities(result.image.spec())
          == std::vector<float> { 0.64f, 0.33f, 0.3f, 0.6f, 0.15f, 0.06f, 0.313f, 0.329f });
    CHECK(result.image.spec().get_string_attribute("colorInteropID") == "lin_rec709_scene");
    // A focus map is false colour: it names no space.
    REQUIRE(render_with(scene, with({ { "output", "focusmap" } }), result, error));
    CHECK(named_chromaticities(result.image.spec()).empty());
    CHECK(result.image.spec().get_string_attribute("colorInteropID").empty());

    // Each result, read back and defocused again with no colour setting,
    // is taken in the space it was written in: the same pixels as naming
    // that space.
    for (const char* space : { "ACEScg", "lin_rec709" }) {
        INFO(space);
        const std::string written = dir + "/written_" + space + ".exr";
        REQUIRE(render_with(scene, with({ { "tocolorspace", space } }), result, error));
        REQUIRE(result.image.write(written));
        const Settings again = with({ { "depth", scene }, { "tocolorspace", "srgb_tx" } });
        Settings named = again;
        named.push_back({ "iscolorspace", space });
        const auto diff = OIIO::ImageBufAlgo::compare(rendered(written, again),
                                                      rendered(written, named), 0.0f, 0.0f);
        CHECK(diff.maxerror == 0.0);
    }
}

TEST_CASE("a preview is the display window through a display's view, over black unless alpha "
          "is kept")
{
    const Settings camera = { { "focal", "50" }, { "fstop", "1.8" }, { "focus", "4" } };
    FrameResult result;
    std::string error;
    REQUIRE(render_with(example_scene(), camera, result, error));
    ImageBuf preview;
    REQUIRE(preview_image(result, "", "", false, preview, error));
    CHECK(preview.roi() == ROI(0, 320, 0, 180, 0, 1, 0, 3));
    // OIIO tags the EXR input with its generic "Linear", taken as linear
    // Rec.709: the preview is OCIO's sRGB display, ACES 1.0 SDR video view,
    // of that.
    OCIO::ConstConfigRcPtr config = OCIO::Config::CreateFromFile(SHIPPED_OCIO_CONFIG);
    OCIO::ConstCPUProcessorRcPtr to_display =
        config->getProcessor("Linear Rec.709 (sRGB)", "sRGB", "ACES 1.0 - SDR Video",
                             OCIO::TRANSFORM_DIR_FORWARD)
            ->getDefaultCPUProcessor();
    int compared = 0;
    for (int y = 5; y < 180; y += 17)
        for (int x = 5; x < 320; x += 23) {
            float linear[4], shown[3];
            result.image.getpixel(x, y, linear);
            preview.getpixel(x, y, shown);
            if (linear[3] < 0.999f)
                continue;
            to_display->applyRGB(linear);
            for (int c = 0; c < 3; ++c)
                CHECK(shown[c] == Approx(std::clamp(linear[c], 0.0f, 1.0f)).margin(1e-4));
            ++compared;
        }
    CHECK(compared > 50);

    // A half-transparent layer in focus: over black the preview shows its
    // premultiplied colour, whatever a viewer puts behind it.
    const std::string half = scratch_dir("color_preview") + "/half.exr";
    write_uniform_image(half, { "R", "G", "B", "A", "Z" }, { 0.09f, 0.09f, 0.09f, 0.5f, 4.0f });
    Settings linear = camera;
    linear.push_back({ "iscolorspace", "lin_rec709" });
    REQUIRE(render_with(half, linear, result, error));
    ImageBuf kept;
    REQUIRE(preview_image(result, "", "Raw", false, preview, error));
    REQUIRE(preview_image(result, "", "Raw", true, kept, error));
    CHECK(preview.nchannels() == 3);
    CHECK(kept.nchannels() == 4);
    CHECK(preview.getchannel(8, 8, 0, 0) == Approx(0.09f).margin(1e-5));  // Raw: as they are
    CHECK(kept.getchannel(8, 8, 0, 3) == Approx(0.5f).margin(1e-5));

    CHECK_FALSE(preview_image(result, "Projector", "", false, preview, error));
    CHECK(one_line_error(error, "displays: sRGB"));
    CHECK_FALSE(preview_image(result, "", "Film", false, preview, error));
    CHECK(one_line_error(error, "views: ACES 1.0 - SDR Video, Raw"));
}
