// The OpenImageIO plugin, through the real programs: oiiotool and Python's
// OpenImageIO open a .dof scene as the image defocus renders from it.
#define CATCH_CONFIG_EXTERNAL_INTERFACES  // listeners
#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <map>
#include <thread>

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imagecache.h>
#include <OpenImageIO/strutil.h>

#include <defocus/io/shot_file.h>

#include "test_support.h"

using namespace defocus_test;
using namespace OIIO;
using Strutil::fmt::format;

namespace {

/// oiiotool and python3 load the plugin; a sanitized plugin needs the
/// sanitizer runtime loaded into them first.
std::string plugin_environment()
{
    const std::string preload = SANITIZER_PRELOAD;
    return (preload.empty() ? "" : "LD_PRELOAD=" + preload + " ") + "OIIO_LIBRARY_PATH=" PLUGIN_DIR " ";
}
const std::string with_plugin = plugin_environment();

/// A .dof (85 mm f/1.4, focus 3 m) of a generated layered scene: the same
/// scene with or without the shared data, so that the plugin is tested
/// alike everywhere. (Garden's, used when present, made them four times
/// as long under the sanitizers; every check here holds on either.)
std::string scene_dof()
{
    static std::string dof;
    if (!dof.empty())
        return dof;
    const std::string dir = scratch_dir("plugin_scene");
    const std::string scene = dir + "/scene.exr";
    std::string log;
    REQUIRE(run(format("{} {} --width 320 --height 180", MAKE_EXAMPLE_SCENE_BIN, scene), log) == 0);
    dof = dir + "/scene.dof";
    REQUIRE(run(format("{} {} --focal 85 --fstop 1.4 --focus 3 --save-scene {}", DEFOCUS_BIN,
                       scene, dof),
                log) == 0);
    return dof;
}

/// The defocus command's own render of a .dof, with extra options.
std::string cli_render(const std::string& dof, const std::string& options = "")
{
    static const std::string dir = scratch_dir("plugin_cli");
    static int count = 0;
    const std::string out = format("{}/cli{}.exr", dir, ++count);
    std::string log;
    INFO(log);
    REQUIRE(run(format("{} {} -o {} -q {}", DEFOCUS_BIN, dof, out, options), log) == 0);
    return out;
}

/// Equal windows, pixel type and pixels, to the bit.
void require_identical(const std::string& a, const std::string& b)
{
    ImageBuf x(a), y(b);
    REQUIRE(x.read());
    REQUIRE(y.read());
    CHECK(x.spec().roi() == y.spec().roi());
    CHECK(x.spec().full_x == y.spec().full_x);
    CHECK(x.spec().full_width == y.spec().full_width);
    CHECK(x.spec().full_height == y.spec().full_height);
    CHECK(x.spec().format == y.spec().format);
    const auto diff = ImageBufAlgo::compare(x, y, 0.0f, 0.0f);
    CHECK(diff.nfail == 0);
    CHECK(diff.maxerror == 0.0);
}

}  // namespace

TEST_CASE("oiiotool opens a .dof as the image the defocus command renders from it")
{
    const std::string dof = scene_dof();
    const std::string out = scratch_dir("plugin_oiiotool") + "/a.exr";
    std::string log;
    REQUIRE(run(with_plugin + OIIOTOOL_BIN + " " + dof + " -o " + out, log) == 0);
    require_identical(out, cli_render(dof));

    // A configuration hint overrides the scene's value, as the flag does.
    // (OIIO 2.4's oiiotool passes hints with --iconfig; it ignores unknown
    // -i: modifiers.)
    const std::string hinted = scratch_dir("plugin_oiiotool") + "/b.exr";
    REQUIRE(run(with_plugin + OIIOTOOL_BIN + " --iconfig dof:focus 1.25 --iconfig dof:fstop 2 "
                    + dof + " -o " + hinted,
                log) == 0);
    require_identical(hinted, cli_render(dof, "--focus 1.25 --fstop 2"));
}

TEST_CASE("AOVs, a holdout and a deep result reach oiiotool through the plugin as through the "
          "command")
{
    const std::string dof = scene_dof();
    // The scene held out by itself: each layer cut by what stands in front.
    defocus::Shot shot;
    std::string error;
    REQUIRE(defocus::load_shot(dof, shot, error));
    const std::string scene = shot.inputs.at(0);
    const std::string dir = scratch_dir("plugin_aov");
    const std::pair<std::string, std::string> cases[] = {
        { "dof:aov confidence", "--aov confidence" },
        { "dof:aov coc", "--aov coc" },
        { "dof:holdout " + scene, "--holdout " + scene },
        { "dof:deep on", "--deep" },
    };
    int count = 0;
    for (const auto& [hint, option] : cases) {
        INFO(option);
        const std::string out = format("{}/{}.exr", dir, ++count);
        std::string log;
        INFO(log);
        REQUIRE(run(with_plugin + OIIOTOOL_BIN + " --iconfig " + hint + " " + dof + " -o " + out,
                    log) == 0);
        const ImageSpec spec = read_spec(out);
        if (Strutil::contains(hint, "aov")) {
            defocus::Aov aov;
            REQUIRE(defocus::parse_aov(Strutil::splits(hint, " ")[1], aov));
            const std::vector<std::string>& names = defocus::aov_channel_names(aov);
            REQUIRE(spec.nchannels == 4 + int(names.size()));
            CHECK(std::vector<std::string>(spec.channelnames.begin() + 4,
                                           spec.channelnames.end())
                  == names);
        }
        CHECK(spec.deep == Strutil::contains(hint, "deep"));
        require_identical(out, cli_render(dof, option));
    }
}

TEST_CASE("a .dof's data channels read through the plugin as the command writes them, in float")
{
    const std::string dof = scene_dof();
    const std::string out = scratch_dir("plugin_data") + "/data.exr";
    std::string log;
    INFO(log);
    REQUIRE(run(with_plugin + OIIOTOOL_BIN + " --iconfig dof:data_channels auto " + dof + " -o "
                    + out,
                log) == 0);
    const std::string cli = cli_render(dof, "--data-channels auto");
    const ImageSpec spec = read_spec(out), written = read_spec(cli);
    CHECK(spec.channelnames == written.channelnames);
    CHECK(spec.channelindex("ZFront") >= 0);
    // oiiotool writes every channel in the format the plugin reports: float
    // keeps data channels whole, and holds the command's colour exactly.
    CHECK(spec.format == TypeFloat);
    CHECK(written.channelformat(written.channelindex("ZFront")) == TypeFloat);
    const auto diff = ImageBufAlgo::compare(ImageBuf(out), ImageBuf(cli), 0.0f, 0.0f);
    CHECK(diff.nfail == 0);
    CHECK(diff.maxerror == 0.0);
}

TEST_CASE("oiiotool renders each frame of a sequence scene: shot.#.dof, or --iconfig dof:frame")
{
    // A three-frame sequence with a focus pull from 1 m to 8 m.
    const std::string dir = scratch_dir("plugin_sequence");
    std::string log;
    REQUIRE(run(format("{} {}/seq.0001.exr --width 160 --height 90", MAKE_EXAMPLE_SCENE_BIN, dir),
                log) == 0);
    for (const char* frame : { "0002", "0003" })
        REQUIRE(Filesystem::copy(dir + "/seq.0001.exr", dir + "/seq." + frame + ".exr"));
    REQUIRE(run(format("{} {}/seq.#.exr --frames 1-3 --focus 1:1,3:8 --focal 50 --fstop 1.8 "
                       "--save-scene {}/seq.dof",
                       DEFOCUS_BIN, dir, dir),
                log) == 0);
    // oiiotool tells a plugin nothing of its --frames: the frame goes in
    // as a hint, which oiiotool expands per frame.
    REQUIRE(run(format("{}{} --frames 1-3 --iconfig dof:frame {{FRAME_NUMBER}} {}/seq.dof -o "
                       "{}/out.#.exr",
                       with_plugin, OIIOTOOL_BIN, dir, dir),
                log) == 0);
    for (int frame : { 1, 2, 3 }) {
        INFO("frame " << frame);
        require_identical(format("{}/out.{:04d}.exr", dir, frame),
                          cli_render(dir + "/seq.dof", format("--frames {}", frame)));
    }
    CHECK(read_spec(dir + "/out.0001.exr").get_float_attribute("defocus:focusDistance") == 1.0f);
    CHECK(read_spec(dir + "/out.0003.exr").get_float_attribute("defocus:focusDistance") == 8.0f);

    // The natural form: a frame pattern on the .dof's name. seq.0002.dof
    // does not exist, so it is frame 2 of seq.dof.
    REQUIRE(run(format("{}{} --frames 1-3 {}/seq.#.dof -o {}/named.#.exr", with_plugin,
                       OIIOTOOL_BIN, dir, dir),
                log) == 0);
    for (int frame : { 1, 2, 3 }) {
        INFO("frame " << frame);
        require_identical(format("{}/named.{:04d}.exr", dir, frame),
                          format("{}/out.{:04d}.exr", dir, frame));
    }
    // A number no sequence file explains is still no such file.
    CHECK(run(format("{}{} {}/other.0002.dof -o {}/x.exr", with_plugin, OIIOTOOL_BIN, dir, dir),
              log) != 0);

    // The same .dof opened for every frame without one gives the first
    // frame each time: said once.
    REQUIRE(run(format("{}{} --frames 1-3 {}/seq.dof -o {}/same.#.exr", with_plugin,
                       OIIOTOOL_BIN, dir, dir),
                log) == 0);
    CHECK(Strutil::contains(log, "is a sequence opened again without a frame"));
    CHECK(log.find("opened again") == log.rfind("opened again"));
    CHECK_THAT(log, Catch::Contains("seq.#.dof"));
}

TEST_CASE("through the plugin a gap in the input sequence is an error, or held when the .dof says")
{
    const std::string dir = scratch_dir("plugin_missing_frames");
    std::string log;
    REQUIRE(run(format("{} {}/seq.0001.exr --width 64 --height 36", MAKE_EXAMPLE_SCENE_BIN, dir),
                log) == 0);
    REQUIRE(Filesystem::copy(dir + "/seq.0001.exr", dir + "/seq.0003.exr"));
    auto dof = [&](const std::string& name, const std::string& missing) {
        REQUIRE(Filesystem::write_text_file(
            dir + "/" + name, R"({"version": 1, "inputs": ["seq.#.exr"], "scene": {"frames": "1-3")"
                                  + missing + R"(}, "camera": {"focus": 3}})"));
    };
    dof("strict.dof", "");
    dof("hold.dof", R"(, "missing_frames": "hold")");
    CHECK(run(format("{}{} --info {}/strict.dof", with_plugin, OIIOTOOL_BIN, dir), log) != 0);
    CHECK(Strutil::contains(log, "seq.0002.exr: no such file; frames with input files missing: 2"));
    REQUIRE(run(format("{}{} --iconfig dof:frame 2 {}/hold.dof -o {}/held.exr", with_plugin,
                       OIIOTOOL_BIN, dir, dir),
                log) == 0);
    require_identical(dir + "/held.exr", cli_render(dir + "/hold.dof", "--frames 1"));
}

TEST_CASE("oiiotool --info reports the spec without rendering")
{
    // Pixels that cannot be read: open() must not need them, so it cannot
    // be rendering (a timed comparison with a render said the same, less
    // surely, and grew flaky as rendering got faster).
    const std::string dir = scratch_dir("plugin_info");
    const std::string scene = dir + "/scene.exr", truncated = dir + "/truncated.exr";
    std::string log;
    REQUIRE(run(format("{} {} --width 320 --height 180", MAKE_EXAMPLE_SCENE_BIN, scene), log) == 0);
    std::string bytes;
    REQUIRE(Filesystem::read_text_file(scene, bytes));
    Filesystem::write_text_file(truncated, bytes.substr(0, bytes.size() / 8));
    REQUIRE(run(format("{} {} --focal 50 --fstop 2 --focus 4 -d float --save-scene {}/t.dof",
                       DEFOCUS_BIN, truncated, dir),
                log) == 0);
    REQUIRE(run(with_plugin + OIIOTOOL_BIN + " --info -v " + dir + "/t.dof", log) == 0);
    CHECK(Strutil::contains(log, "352 x  212, 4 channel, float dof"));  // 16 px overscan
    CHECK(Strutil::contains(log, "channel list: R, G, B, A"));
    CHECK(Strutil::contains(log, "pixel data origin: x=-16, y=-16"));
    CHECK(Strutil::contains(log, "full/display size: 320 x 180"));
    CHECK(Strutil::contains(log, "defocus:focusDistance: 4"));
    CHECK(Strutil::contains(log, "defocus:exampleCamera"));  // the input's metadata
    // Reading the pixels renders, and that fails here, as an error.
    CHECK(run(with_plugin + OIIOTOOL_BIN + " " + dir + "/t.dof -o " + dir + "/x.exr", log) == 1);
    CHECK(Strutil::contains(log, "truncated.exr: corrupt or truncated OpenEXR file"));
}

TEST_CASE("with --grow the plugin's window holds all the light the defocus command spreads")
{
    // The plugin gives the window before it renders, from the headers: it
    // must be the largest the blur can make, past the edges the layers are
    // extended by and whatever reach each aperture has.
    const std::string dir = scratch_dir("plugin_grow");
    std::string log;
    REQUIRE(run(format("{} {}/scene.exr --width 160 --height 90", MAKE_EXAMPLE_SCENE_BIN, dir),
                log) == 0);
    for (const char* aperture : { "disc", "polygon", "smooth" }) {
        INFO(aperture);
        const std::string dof = format("{}/{}.dof", dir, aperture);
        REQUIRE(run(format("{} {}/scene.exr --focal 100 --fstop 1 --focus 0.5 --max-blur 60 "
                           "--aperture {} --grow -d float --save-scene {}",
                           DEFOCUS_BIN, dir, aperture, dof),
                    log) == 0);
        const std::string via_plugin = format("{}/{}_plugin.exr", dir, aperture);
        REQUIRE(run(with_plugin + OIIOTOOL_BIN + " " + dof + " -o " + via_plugin, log) == 0);
        const ImageBuf command = read_image(cli_render(dof)), plugin = read_image(via_plugin);
        REQUIRE(command.initialized());
        REQUIRE(plugin.initialized());
        CHECK(OIIO::roi_union(plugin.roi(), command.roi()) == plugin.roi());
        const ImageBuf same_window = ImageBufAlgo::crop(plugin, command.roi());
        CHECK(ImageBufAlgo::compare(same_window, command, 0.0f, 0.0f).maxerror == 0.0);
        const auto in_plugin = ImageBufAlgo::computePixelStats(plugin);
        const auto in_command = ImageBufAlgo::computePixelStats(command);
        for (int c = 0; c < 4; ++c)
            CHECK(in_plugin.sum[c] == Approx(in_command.sum[c]).epsilon(1e-9));
    }
}

TEST_CASE("Python's ImageBuf opens a .dof with the same pixels, and takes hints")
{
    const std::string dof = scene_dof();
    const std::string plain = cli_render(dof), hinted = cli_render(dof, "--focus 1.25");
    const std::string script = format(
        "import OpenImageIO as oiio\n"
        "def same(a, b):\n"
        "    r = oiio.ImageBufAlgo.compare(a, oiio.ImageBuf(b), 0.0, 0.0)\n"
        "    return r.nfail == 0 and r.maxerror == 0.0 and a.roi == oiio.ImageBuf(b).roi\n"
        "config = oiio.ImageSpec()\n"
        "config.attribute('dof:focus', 1.25)\n"
        "print('plain', same(oiio.ImageBuf('{}'), '{}'))\n"
        "print('hinted', same(oiio.ImageBuf('{}', 0, 0, config), '{}'))\n",
        dof, plain, dof, hinted);
    const std::string path = scratch_dir("plugin_python") + "/check.py";
    Filesystem::write_text_file(path, script);
    std::string log;
    const int status = run(with_plugin + PYTHON_BIN + " " + path, log);
    INFO(log);
    REQUIRE(status == 0);
    CHECK(Strutil::contains(log, "plain True"));
    CHECK(Strutil::contains(log, "hinted True"));
}

TEST_CASE("a broken .dof is an error line from oiiotool, never a crash")
{
    const std::string dir = scratch_dir("plugin_errors");
    Filesystem::write_text_file(dir + "/bad_json.dof", "{\"version\": 1, \"inputs\": [");
    Filesystem::write_text_file(dir + "/missing.dof",
                                "{\"version\": 1, \"inputs\": [\"gone.exr\"], \"camera\": {\"focus\": 3}}");
    Filesystem::write_text_file(dir + "/bad_space.dof",
                                "{\"version\": 1, \"inputs\": [\"bad_json.dof\"], \"camera\": "
                                "{\"focus\": 3}, \"color\": {\"input\": \"nospace\"}}");
    // A number that overflows a double made nlohmann throw out_of_range,
    // past the parser's catch, out of the plugin, ending oiiotool.
    Filesystem::write_text_file(dir + "/overflow.dof",
                                "{\"version\": 1, \"inputs\": [], \"camera\": {\"focus\": 96e379}}");
    // Windows OpenImageIO cannot allocate crashed it: a grown window of
    // 100052x100036 from a blur of 1e5 px, and a damaged input declaring
    // 200000x200000. open() refuses a spec beyond the memory limit.
    write_exr_header_only(dir + "/giant.exr", 200000, 200000);
    write_exr_header_only(dir + "/small.exr", 64, 64);
    Filesystem::write_text_file(dir + "/giant_input.dof",
                                "{\"version\": 1, \"inputs\": [\"giant.exr\"], \"camera\": "
                                "{\"focus\": 3}}");
    Filesystem::write_text_file(dir + "/giant_blur.dof",
                                "{\"version\": 1, \"inputs\": [\"small.exr\"], \"camera\": "
                                "{\"focus\": 3, \"max_blur\": 100000}, \"output\": "
                                "{\"window\": \"grown\"}}");
    // An error from a nested scene file names each file once.
    Filesystem::write_text_file(dir + "/missing_sequence.dof",
                                "{\"version\": 1, \"inputs\": [\"gone.#.exr\"], \"camera\": "
                                "{\"focus\": 3}}");
    Filesystem::write_text_file(dir + "/nested.dof",
                                "{\"version\": 1, \"inputs\": [\"missing_sequence.dof\"], "
                                "\"camera\": {\"focus\": 3}}");
    // Settings are named as a .dof writes them.
    Filesystem::write_text_file(dir + "/no_focus.dof",
                                "{\"version\": 1, \"inputs\": [\"small.exr\"], \"camera\": "
                                "{\"from_file\": false}}");
    const std::pair<const char*, const char*> cases[] = {
        { "nested.dof", "nested.dof: missing_sequence.dof: gone.#.exr: no files match (give "
                        "scene.frames to name them)" },
        { "giant_input.dof", "a 200000x200000 result needs 596 GB, more than the memory limit" },
        { "giant_input.dof", "(scene.memory_limit)" },
        { "no_focus.dof", "camera.focus DIST or camera.focus_at X,Y is required" },
        { "giant_blur.dof", "a window grown by blur up to 100000 px needs" },
        { "bad_json.dof", "bad_json.dof: not valid JSON: parse error at line 1" },
        { "overflow.dof", "overflow.dof: not valid JSON: number overflow" },
        { "missing.dof", "missing.dof: inputs: " },
        { "bad_space.dof", "bad_space.dof" },
    };
    for (const auto& [file, message] : cases) {
        INFO(file);
        std::string log;
        CHECK(run(with_plugin + OIIOTOOL_BIN + " " + dir + "/" + file + " -o " + dir + "/out.exr",
                  log) == 1);
        CHECK(Strutil::contains(log, "oiiotool ERROR"));
        CHECK(Strutil::contains(Strutil::replace(log, dir + "/", "", true), message));
        CHECK_FALSE(Filesystem::exists(dir + "/out.exr"));
    }
}

TEST_CASE("four threads reading one .dof through an ImageCache get identical pixels")
{
    const std::string dof = scene_dof();
    ImageBuf expected(cli_render(dof));
    REQUIRE(expected.read(0, 0, true, TypeFloat));
    const ROI roi = expected.roi();
    auto cache = ImageCache::create(/*shared=*/false);
    std::vector<std::vector<float>> pixels(4, std::vector<float>(roi.npixels() * 4));
    std::vector<int> ok(4, 0);
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
        threads.emplace_back([&, t] {
            ok[t] = cache->get_pixels(ustring(dof), 0, 0, roi.xbegin, roi.xend, roi.ybegin,
                                      roi.yend, 0, 1, TypeFloat, pixels[t].data());
        });
    for (std::thread& t : threads)
        t.join();
    std::vector<float> reference(roi.npixels() * 4);
    REQUIRE(expected.get_pixels(roi, TypeFloat, reference.data()));
    for (int t = 0; t < 4; ++t) {
        INFO("thread " << t << ": " << cache->geterror());
        REQUIRE(ok[t]);
        // The first value that differs, if any (the whole vector would
        // take Catch minutes to print).
        const size_t differs = size_t(
            std::mismatch(pixels[t].begin(), pixels[t].end(), reference.begin()).first
            - pixels[t].begin());
        CHECK(differs == reference.size());
    }
    ImageCache::destroy(cache);
}

TEST_CASE("every damaged EXR behind a .dof is an error, never a crash of the host")
{
    if (shared_data().empty()) {
        WARN("skipped: no shared data (the Damaged corpus)");
        return;
    }
    const std::string damaged = shared_data() + "/openexr-images/Damaged";
    std::vector<std::string> files;
    Filesystem::get_directory_entries(damaged, files);
    REQUIRE(files.size() >= 180);
    const std::string dof = scratch_dir("plugin_damaged") + "/damaged.dof";
    for (const std::string& file : files) {
        INFO(file);
        Filesystem::write_text_file(
            dof, format("{{\"version\": 1, \"inputs\": [\"{}\"], \"camera\": {{\"focus\": 3}}}}",
                        file));
        // Opened afresh each time: no cache between the files.
        auto in = ImageInput::open(dof);
        if (!in) {
            CHECK(Strutil::contains(OIIO::geterror(), Filesystem::filename(file)));
            continue;
        }
        std::vector<float> pixels(size_t(in->spec().image_pixels()) * in->spec().nchannels);
        CHECK_FALSE(in->read_image(0, 0, 0, in->spec().nchannels, TypeFloat, pixels.data()));
        CHECK(Strutil::contains(in->geterror(), Filesystem::filename(file)));
    }
}

TEST_CASE("a .dof that reaches itself is an error in every host, never a stack overflow")
{
    const std::string dir = scratch_dir("plugin_cycles");
    std::string log;
    REQUIRE(run(format("{} {}/scene.exr --width 64 --height 36", MAKE_EXAMPLE_SCENE_BIN, dir),
                log) == 0);
    auto write = [&](const std::string& name, const std::string& body) {
        REQUIRE(Filesystem::write_text_file(dir + "/" + name,
                                            "{\"version\": 1, " + body + "}"));
    };
    write("self.dof", R"("inputs": ["self.dof"], "camera": {"focus": 3})");
    write("a.dof", R"("inputs": ["b.dof"], "camera": {"focus": 3})");
    write("b.dof", R"("inputs": ["a.dof"], "camera": {"focus": 3})");
    write("mask.dof", R"("inputs": ["scene.exr"], "camera": {"focus": 3},
                         "aperture": {"shape": "mask", "mask": "mask.dof"})");
    write("psf.dof", R"("inputs": ["scene.exr"], "camera": {"focus": 3},
                        "aperture": {"psf_image": "psf.dof"})");
    // Another name of a.dof: cycles are found by file identity.
    REQUIRE(symlink("a.dof", (dir + "/alias.dof").c_str()) == 0);
    write("c.dof", R"("inputs": ["alias.dof"], "camera": {"focus": 3})");
    // A chain of distinct files deeper than scene files may nest.
    for (int i = 1; i <= 10; ++i)
        write(format("n{}.dof", i), format(R"("inputs": ["n{}.dof"])", i + 1));
    write("n11.dof", R"("inputs": ["scene.exr"], "camera": {"focus": 3})");
    // A .dof frame pattern that leads back to itself only shows at run time.
    write("p.0001.dof", R"("inputs": ["p.#.dof"], "scene": {"frames": "1"})");

    const std::map<std::string, std::string> expected = {
        { "self.dof", "self.dof: refers to itself" },
        { "a.dof", "a.dof: refers to itself through b.dof" },
        { "mask.dof", "mask.dof: refers to itself" },
        { "psf.dof", "psf.dof: refers to itself" },
        { "c.dof", "alias.dof: refers to itself through b.dof" },
        { "n1.dof", "scene files nested more than 8 deep" },
        { "p.0001.dof", "scene files nested more than 8 deep" },
    };
    for (const auto& [dof, message] : expected) {
        INFO(dof);
        const std::string path = dir + "/" + dof;
        for (const std::string& command :
             { format("{}{} --info {}", with_plugin, OIIOTOOL_BIN, path),
               format("{}{} {} -o {}/out.exr", with_plugin, OIIOTOOL_BIN, path, dir),
               format("{}{} {} -o {}/out.exr --focus 3", with_plugin, DEFOCUS_BIN, path, dir) }) {
            INFO(command);
            const int status = run(command, log);
            INFO(log);
            CHECK(status != 0);
            CHECK(status < 128);  // not ended by a signal
            CHECK(Strutil::contains(Strutil::replace(log, dir + "/", "", true), message));
        }
        // The library's own reading says the same, without the plugin.
        ImageBuf image(path);
        CHECK_FALSE(image.read());
        CHECK(Strutil::contains(Strutil::replace(image.geterror(), dir + "/", "", true),
                                message));
    }
    CHECK_FALSE(Filesystem::exists(dir + "/out.exr"));
}

TEST_CASE("the plugin reads no row outside the image, and no input changed since open")
{
    const std::string dir = scratch_dir("plugin_stale");
    std::string log;
    REQUIRE(run(format("{} {}/scene.exr --width 64 --height 36", MAKE_EXAMPLE_SCENE_BIN, dir),
                log) == 0);
    REQUIRE(Filesystem::write_text_file(
        dir + "/shot.dof",
        R"({"version": 1, "inputs": ["scene.exr"], "camera": {"focus": 3}})"));
    auto in = ImageInput::open(dir + "/shot.dof");
    REQUIRE(in);
    const ImageSpec spec = in->spec();
    std::vector<float> row(size_t(spec.width) * spec.nchannels, -7.0f);
    // Rows past either end used to come back as whatever memory held.
    for (int y : { spec.y - 1, spec.y + spec.height, spec.y + spec.height + 1000 }) {
        INFO("row " << y);
        CHECK_FALSE(in->read_scanline(y, 0, TypeFloat, row.data()));
        CHECK(Strutil::contains(in->geterror(), "outside the image's rows"));
    }
    CHECK(in->read_scanline(spec.y, 0, TypeFloat, row.data()));
    in->close();

    // The input replaced by a larger render after open(): its pixels would
    // come back under the spec of the old one.
    in = ImageInput::open(dir + "/shot.dof");
    REQUIRE(in);
    REQUIRE(run(format("{} {}/bigger.exr --width 128 --height 72", MAKE_EXAMPLE_SCENE_BIN, dir),
                log) == 0);
    REQUIRE(Filesystem::rename(dir + "/bigger.exr", dir + "/scene.exr"));
    std::vector<float> pixels(size_t(in->spec().image_pixels()) * in->spec().nchannels);
    CHECK_FALSE(in->read_image(0, 0, 0, in->spec().nchannels, TypeFloat, pixels.data()));
    CHECK(Strutil::contains(in->geterror(), "scene.exr changed since the scene was opened"));
    // Opened again, it is the new scene.
    in = ImageInput::open(dir + "/shot.dof");
    REQUIRE(in);
    CHECK(in->spec().full_width == 128);
}

TEST_CASE("a deep result's rows and channels read through the plugin as the whole image has them")
{
    ImageSpec config;
    config.attribute("dof:deep", "on");
    auto in = ImageInput::open(scene_dof(), &config);
    REQUIRE(in);
    const ImageSpec spec = in->spec();
    REQUIRE(spec.deep);
    DeepData all, rows;
    REQUIRE(in->read_native_deep_image(0, 0, all));
    // Rows from the middle, alpha and Z only.
    const int y0 = spec.y + spec.height / 2, y1 = y0 + 3;
    REQUIRE(in->read_native_deep_scanlines(0, 0, y0, y1, 0, 3, 5, rows));
    REQUIRE(rows.channels() == 2);
    CHECK(rows.channelname(0) == "A");
    CHECK(rows.channelname(1) == "Z");
    int64_t samples = 0;
    for (int64_t p = 0; p < rows.pixels(); ++p) {
        const int64_t whole = int64_t(y0 - spec.y) * spec.width + p;
        REQUIRE(rows.samples(p) == all.samples(whole));
        samples += rows.samples(p);
        for (int s = 0; s < rows.samples(p); ++s) {
            CHECK(rows.deep_value(p, 0, s) == all.deep_value(whole, 3, s));
            CHECK(rows.deep_value(p, 1, s) == all.deep_value(whole, 4, s));
        }
    }
    CHECK(samples > rows.pixels());  // layers overlap there
    // Rows outside the image are refused, not read.
    CHECK_FALSE(in->read_native_deep_scanlines(0, 0, spec.y - 1, spec.y + 1, 0, 0, 6, rows));
}

namespace {

/// In this process the plugin is found through the searchpath attribute,
/// set before any image is opened.
struct PluginSearchPath : Catch::TestEventListenerBase {
    using TestEventListenerBase::TestEventListenerBase;
    void testRunStarting(const Catch::TestRunInfo&) override
    {
        OIIO::attribute("plugin_searchpath", PLUGIN_DIR);
    }
};

}  // namespace

CATCH_REGISTER_LISTENER(PluginSearchPath)
