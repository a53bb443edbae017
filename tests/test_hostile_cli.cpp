// Hostile and careless use of the tools (round 3 of hostile testing): what
// a run reads is never destroyed, a sequence never drops a frame quietly.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>

#include "test_support.h"

using namespace defocus_test;
using namespace OIIO;
using Strutil::fmt::format;

namespace {

std::string file_bytes(const std::string& path)
{
    std::string bytes;
    Filesystem::read_text_file(path, bytes);
    return bytes;
}


bool same_pixels(const std::string& a, const std::string& b)
{
    const ImageBuf x = read_image(a), y = read_image(b);
    return x.initialized() && y.initialized()
           && ImageBufAlgo::compare(x, y, 0.0f, 0.0f).nfail == 0;
}

}  // namespace

TEST_CASE("no run overwrites a file it reads: depth, mask, PSF, scene file, by any name")
{
    const std::string dir = scratch_dir("hostile_overwrite");
    REQUIRE(Filesystem::copy(example_scene(), dir + "/scene.exr"));
    REQUIRE(Filesystem::copy(std::string(EXAMPLES_DIR) + "/psf/blades7.exr", dir + "/mask.exr"));
    REQUIRE(Filesystem::copy(std::string(EXAMPLES_DIR) + "/psf/disc_rim.exr", dir + "/psf.exr"));
    write_uniform_image(dir + "/rgba.exr", { "R", "G", "B", "A" }, { 0.5f, 0.5f, 0.5f, 1.0f });
    write_uniform_image(dir + "/depth.exr", { "Z" }, { 3.0f });
    REQUIRE(link((dir + "/scene.exr").c_str(), (dir + "/hardlink.exr").c_str()) == 0);
    REQUIRE(symlink("scene.exr", (dir + "/symlink.exr").c_str()) == 0);
    std::string log;
    REQUIRE(run(format("cd {} && {} scene.exr --focus 4 --save-scene shot.dof", dir, defocus_bin),
                log) == 0);

    const std::string cam = " --focal 50 --fstop 2 --focus 3";
    const struct {
        std::string command, written, read;
    } cases[] = {
        { defocus_bin + " rgba.exr --depth depth.exr -o depth.exr" + cam, "depth.exr", "depth.exr" },
        { defocus_bin + " scene.exr --aperture mask:mask.exr -o mask.exr" + cam, "mask.exr",
          "mask.exr" },
        { defocus_bin + " scene.exr --psf-image psf.exr -o psf.exr" + cam, "psf.exr", "psf.exr" },
        { defocus_bin + " shot.dof --save-scene shot.dof", "shot.dof", "shot.dof" },
        { defocus_bin + " shot.dof -o out.exr --save-scene ./shot.dof", "./shot.dof",
          "shot.dof" },
        { defocus_bin + " scene.exr -o out.exr --preview scene.exr" + cam, "scene.exr",
          "scene.exr" },
        { defocus_bin + " scene.exr -o hardlink.exr" + cam, "hardlink.exr", "scene.exr" },
        { defocus_bin + " symlink.exr -o scene.exr" + cam, "scene.exr", "symlink.exr" },
        { std::string(LAYERIZE_BIN) + " scene.exr -o hardlink.exr" + cam, "hardlink.exr",
          "scene.exr" },
        { std::string(LAYERIZE_BIN) + " rgba.exr --depth depth.exr -o depth.exr" + cam,
          "depth.exr", "depth.exr" },
    };
    for (const auto& c : cases) {
        INFO(c.command);
        const std::string before = file_bytes(dir + "/" + c.read);
        CHECK(run("cd " + dir + " && " + c.command, log) != 0);
        INFO(log);
        CHECK(one_line_naming(log, format("{}: would overwrite the input {}", c.written, c.read)));
        CHECK(file_bytes(dir + "/" + c.read) == before);
        CHECK_FALSE(Filesystem::exists(dir + "/out.exr"));
    }
}

TEST_CASE("a sequence with a frame missing is refused, or skips or holds it when told")
{
    const std::string dir = scratch_dir("hostile_missing_frames");
    for (int frame : { 1001, 1002, 1004 })
        REQUIRE(Filesystem::copy(example_scene(), format("{}/plate.{}.exr", dir, frame)));
    const std::string cam = " --focal 50 --fstop 2 --focus 3 -q";
    std::string log;
    // Without --frames the span on disk is 1001-1004, and 1003 is a gap;
    // with them, 1003 is named and not there.
    for (const std::string& frames : { "", " --frames 1001-1004" }) {
        INFO(frames);
        CHECK(run(format("cd {} && {} plate.#.exr -o out.#.exr{}{}", dir, defocus_bin, frames, cam),
                  log)
              == 1);
        CHECK(one_line_naming(log, "plate.1003.exr: no such file; frames with input files "
                                   "missing: 1003"));
        CHECK_FALSE(Filesystem::exists(dir + "/out.1001.exr"));
    }
    // Told to skip: the others are written, and the run says which it left.
    REQUIRE(run(format("cd {} && {} plate.#.exr -o skip.#.exr --missing-frames skip --focal 50 "
                       "--fstop 2 --focus 3",
                       dir, defocus_bin),
                log)
            == 0);
    CHECK(Strutil::contains(log, "frames with input files missing are not rendered "
                                 "(--missing-frames skip): 1003"));
    CHECK(Strutil::contains(log, "3 of 3 frames written"));
    CHECK(Filesystem::exists(dir + "/skip.1004.exr"));
    CHECK_FALSE(Filesystem::exists(dir + "/skip.1003.exr"));
    // Told to hold, through a .dof: frame 1003 is frame 1002's plate.
    REQUIRE(Filesystem::write_text_file(
        dir + "/hold.dof", "{\"version\": 1, \"inputs\": [\"plate.#.exr\"], \"scene\": "
                           "{\"missing_frames\": \"hold\"}, \"camera\": {\"focal\": 50, "
                           "\"fstop\": 2, \"focus\": 3}}"));
    REQUIRE(run(format("cd {} && {} hold.dof -o hold.#.exr -q", dir, defocus_bin), log) == 0);
    CHECK(same_pixels(dir + "/hold.1003.exr", dir + "/hold.1002.exr"));
    CHECK(same_pixels(dir + "/hold.1004.exr", dir + "/skip.1004.exr"));
    // Once the frame is there, a rerun does not take the held frame for it.
    REQUIRE(Filesystem::copy(example_scene(), dir + "/plate.1003.exr"));
    REQUIRE(run(format("cd {} && {} hold.dof -o hold.#.exr --skip-existing -v", dir, defocus_bin),
                log)
            == 0);
    CHECK(Strutil::contains(log, "rendering again: hold.1003.exr"));
    CHECK(Strutil::contains(log, "skipped: hold.1002.exr"));
}

namespace {

/// Runs `argv` in `dir` as a process that first plants, where a temporary
/// file of `target` was once named (".TARGET.HOST.PID.tmp.EXT", which its
/// own process id made predictable), a symbolic link to `victim`. Its exit
/// status.
int run_with_planted_link(const std::string& dir, const std::string& target,
                          const std::string& victim, std::vector<std::string> argv)
{
    const std::string prefix = format("{}/.{}.{}.", dir, target, this_host());
    const std::string suffix = ".tmp" + Filesystem::extension(target);
    std::vector<char*> args;
    for (std::string& a : argv)
        args.push_back(a.data());
    args.push_back(nullptr);
    const pid_t pid = fork();
    if (pid == 0) {
        // Only async-signal-safe calls between fork and exec.
        char link_path[4096];
        char digits[16];
        int n = 0;
        for (pid_t p = getpid(); p > 0; p /= 10)
            digits[n++] = char('0' + p % 10);
        size_t at = 0;
        for (char c : prefix)
            link_path[at++] = c;
        while (n > 0)
            link_path[at++] = digits[--n];
        for (char c : suffix)
            link_path[at++] = c;
        link_path[at] = '\0';
        if (symlink(victim.c_str(), link_path) != 0 || chdir(dir.c_str()) != 0)
            _exit(126);
        execv(args[0], args.data());
        _exit(127);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

}  // namespace

TEST_CASE("a symbolic link planted where a temporary file goes is never written through")
{
    const std::string dir = scratch_dir("hostile_planted_link");
    REQUIRE(Filesystem::copy(example_scene(), dir + "/scene.exr"));
    const std::string victim = dir + "/victim.txt";
    for (const std::string& target : { "out.exr", "out.png", "out.tif", "out.sgi", "shot.dof" }) {
        INFO(target);
        REQUIRE(Filesystem::write_text_file(victim, "another user's precious file"));
        std::vector<std::string> argv = { defocus_bin, "scene.exr", "--focus", "3", "-q" };
        if (target == "shot.dof")
            argv.insert(argv.end(), { "--save-scene", target });
        else
            argv.insert(argv.end(), { "-o", target });
        CHECK(run_with_planted_link(dir, target, victim, argv) == 0);
        CHECK(file_bytes(victim) == "another user's precious file");
        // The target is a file of its own, complete.
        CHECK(Filesystem::is_regular(dir + "/" + target));
        if (target != "shot.dof")
            CHECK(read_image(dir + "/" + target).initialized());
    }
}

TEST_CASE("past the file size limit a write is a one-line error, and leaves no temporary file")
{
    const std::string dir = scratch_dir("hostile_file_size_limit");
    REQUIRE(Filesystem::copy(example_scene(), dir + "/scene.exr"));
    std::string log;
    // SIGXFSZ used to end the process, its temporary file left behind.
    CHECK(run(format("cd {} && ulimit -f 16 && {} scene.exr -o out.exr --focus 3 "
                     "--compression none -q",
                     dir, defocus_bin),
              log)
          == 1);
    CHECK(one_line_naming(log, "out.exr: cannot write"));
    std::vector<std::string> entries;
    Filesystem::get_directory_entries(dir, entries);
    CHECK(entries.size() == 1);  // the scene alone
}

TEST_CASE("a frame cut short is rendered again, not skipped as done")
{
    const std::string dir = scratch_dir("hostile_truncated_frame");
    REQUIRE(Filesystem::copy(example_scene(), dir + "/scene.exr"));
    const std::string args = " scene.exr --frames 1-3 -o out.#.exr --focus 1:3,3:4";
    std::string log;
    REQUIRE(run(format("cd {} && {}{} -q", dir, defocus_bin, args), log) == 0);
    const std::string whole = file_bytes(dir + "/out.0002.exr");
    // A farm task killed as it copied the frame: the header is all there.
    REQUIRE(Filesystem::write_text_file(dir + "/out.0002.exr", whole.substr(0, whole.size() - 50)));
    REQUIRE(run(format("cd {} && {}{} --skip-existing -v", dir, defocus_bin, args), log) == 0);
    CHECK(Strutil::contains(log, "frame 2: rendering again: out.0002.exr is incomplete ("));
    CHECK(Strutil::contains(log, "frame 1: skipped: out.0001.exr is written with these settings"));
    CHECK(Strutil::contains(log, "1 of 1 frames written (2 more skipped"));
    CHECK(file_bytes(dir + "/out.0002.exr") == whole);
}

TEST_CASE("no part is dropped without a word, and 8-bit and sRGB-tagged images are sRGB")
{
    const std::string dir = scratch_dir("hostile_silent_drops");
    std::string log;
    // A layer with depth and a part with colour alone: the second used to
    // vanish from the render.
    ImageSpec layer(16, 16, 5, TypeFloat), beauty(16, 16, 4, TypeFloat);
    layer.channelnames = { "R", "G", "B", "A", "Z" };
    beauty.channelnames = { "R", "G", "B", "A" };
    layer.attribute("name", "bg");
    beauty.attribute("name", "fx");
    {
        auto out = ImageOutput::create(dir + "/parts.exr");
        const ImageSpec specs[] = { layer, beauty };
        REQUIRE(out->open(dir + "/parts.exr", 2, specs));
        const std::vector<float> pixels(16 * 16 * 5, 1.0f);
        REQUIRE(out->write_image(TypeFloat, pixels.data()));
        REQUIRE(out->open(dir + "/parts.exr", beauty, ImageOutput::AppendSubimage));
        REQUIRE(out->write_image(TypeFloat, pixels.data()));
        REQUIRE(out->close());
    }
    CHECK(run(format("{} {}/parts.exr -o {}/o.exr --focus 3", defocus_bin, dir, dir), log) == 1);
    CHECK(one_line_naming(log, "parts.exr: part 1 'fx' has colour but no depth (Z)"));

    // 8- and 16-bit images in the sRGB encoding: tagged (PNG) or not (TIFF).
    write_uniform_image(dir + "/z.exr", { "Z" }, { 3.0f });
    ImageBuf rgba = read_image(example_scene());
    rgba = ImageBufAlgo::channels(rgba, 4, { 0, 1, 2, 3 });
    rgba = ImageBufAlgo::cut(rgba, ROI(0, 16, 0, 16));
    rgba.specmod().erase_attribute("oiio:ColorSpace");
    REQUIRE(rgba.write(dir + "/tagged.png", TypeUInt8));
    REQUIRE(rgba.write(dir + "/untagged8.tif", TypeUInt8));
    REQUIRE(rgba.write(dir + "/untagged16.tif", TypeUInt16));
    REQUIRE(rgba.write(dir + "/untagged_float.tif", TypeFloat));
    const std::string cam = " --depth z.exr --focus 2 -v";
    const struct {
        std::string file, input;
    } inputs[] = {
        { "tagged.png", "input 'sRGB - Texture' (from the file's colour space tag 'sRGB'), "
                        "spread in" },
        { "untagged8.tif", "input 'sRGB - Texture' (a guess: an untagged 8-bit image taken as "
                           "sRGB, as OpenImageIO does)" },
        { "untagged16.tif", "input 'sRGB - Texture' (a guess: an untagged 16-bit image taken as "
                            "sRGB" },
        { "untagged_float.tif", "input 'ACEScg' (a guess: no colour space tag" },
    };
    for (const auto& in : inputs) {
        INFO(in.file);
        REQUIRE(run(format("cd {} && {} {} -o out_{}.exr{}", dir, defocus_bin, in.file, in.file,
                           cam),
                    log) == 0);
        CHECK(Strutil::contains(log, in.input));
    }
    // The tag means what the space named explicitly means.
    REQUIRE(run(format("cd {} && {} tagged.png -o explicit.exr --iscolorspace srgb_tx{}", dir,
                       defocus_bin, cam),
                log) == 0);
    CHECK(same_pixels(dir + "/explicit.exr", dir + "/out_tagged.png.exr"));
    // The names other configs and OpenImageIO give these spaces.
    for (const auto& [alias, space] : std::vector<std::pair<std::string, std::string>> {
             { "sRGB", "sRGB - Texture" }, { "srgb_texture", "sRGB - Texture" },
             { "'Utility - sRGB - Texture'", "sRGB - Texture" },
             { "lin_srgb", "Linear Rec.709 (sRGB)" }, { "Linear", "Linear Rec.709 (sRGB)" },
             { "'Utility - Linear - sRGB'", "Linear Rec.709 (sRGB)" },
             { "scene_linear", "ACEScg" }, { "'ACES - ACEScg'", "ACEScg" } }) {
        INFO(alias);
        REQUIRE(run(format("cd {} && {} untagged_float.tif -o a.exr --iscolorspace {}{}", dir,
                           defocus_bin, alias, cam),
                    log) == 0);
        CHECK(Strutil::contains(log, "input '" + space + "', spread in"));
    }
}

TEST_CASE("a colour channel named as the depth is refused")
{
    const std::string dir = scratch_dir("hostile_depth_channel");
    write_uniform_image(dir + "/rgba.exr", { "R", "G", "B", "A" }, { 0.5f, 0.5f, 0.5f, 1.0f });
    std::string log;
    // Alpha as depth made every pixel 1 m away, or nowhere: a transparent
    // frame, and exit 0.
    for (const std::string& channel : { "A", "G" }) {
        CHECK(run(format("cd {} && {} rgba.exr --depth {} -o out.exr --focus 3", dir, defocus_bin,
                         channel),
                  log)
              == 1);
        CHECK(one_line_naming(log, format("rgba.exr: --depth {}: that is the {} channel of part 0, "
                                          "not a depth",
                                          channel, channel == "A" ? "alpha" : "colour")));
    }
    CHECK_FALSE(Filesystem::exists(dir + "/out.exr"));
}
