// Render farms: frame chunks and the settings hash that makes reruns resume.
#include <map>

#include <catch2/catch.hpp>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/strutil.h>

#include <defocus/io/frames.h>
#include <defocus/io/image_output.h>
#include <defocus/io/settings_hash.h>
#include <defocus/io/shot_file.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using OIIO::Strutil::fmt::format;

TEST_CASE("every frame is in exactly one chunk, chunks are neighbours in order, for any N and step")
{
    for (int count : { 0, 1, 2, 7, 24, 100 })
        for (int step : { 1, 2, 5 })
            for (int n : { 1, 2, 3, 4, 7, 24, 25, 101 }) {
                INFO(count << " frames, step " << step << ", " << n << " chunks");
                std::vector<int> frames;
                for (int i = 0; i < count; ++i)
                    frames.push_back(1001 + i * step);
                std::vector<int> joined;
                size_t smallest = frames.size(), largest = 0;
                for (int k = 1; k <= n; ++k) {
                    const std::vector<int> chunk = chunk_frames(frames, k, n);
                    joined.insert(joined.end(), chunk.begin(), chunk.end());
                    smallest = std::min(smallest, chunk.size());
                    largest  = std::max(largest, chunk.size());
                }
                CHECK(joined == frames);  // each once, in order: chunks are contiguous
                CHECK(largest - std::min(smallest, largest) <= 1);
            }
}

TEST_CASE("a chunk is written K/N and parsed strictly")
{
    int k = 0, n = 0;
    std::string error;
    CHECK(parse_chunk("--chunk", "3/4", k, n, error));
    CHECK((k == 3 && n == 4));
    for (const char* bad : { "0/4", "5/4", "4", "1/0", "a/b", "1/2/3", "-1/4", "1.5/4", "" }) {
        INFO(bad);
        CHECK_FALSE(parse_chunk("--chunk", bad, k, n, error));
        CHECK(OIIO::Strutil::starts_with(error, "--chunk: '"));
    }
}

TEST_CASE("the settings hash changes with a setting, not with how the shot was written")
{
    const std::string dir = scratch_dir("farm_hash");
    Shot shot;
    shot.inputs = { dir + "/plate.#.exr" };
    std::string error;
    REQUIRE(set_shot_setting(shot, "focus", "1001:3,1040:1.2", error));
    REQUIRE(set_shot_setting(shot, "fstop", "1.4", error));
    REQUIRE(set_shot_setting(shot, "aperture", "polygon", error));
    const std::string hash = settings_hash(shot, 1001);
    CHECK(hash.size() == 16);
    CHECK(settings_hash(shot, 1001) == hash);
    CHECK(settings_hash(shot, 1002) != hash);  // another frame

    // Every setting, changed, changes it; the frame list and the memory
    // limit do not change a frame's pixels, nor the hash.
    const std::map<std::string, std::string> changed = {
        { "fstop", "2" }, { "focus", "1001:3,1040:1.3" }, { "focal", "85" },
        { "aperture", "disc" }, { "blades", "7" }, { "max-blur", "100" }, { "layers", "3" },
        { "lens", "optical" }, { "edge", "black" }, { "pixel-type", "float" },
        { "compression", "piz" }, { "window", "display" }, { "spread", "exact" },
        { "tocolorspace", "sRGB" }, { "camera-from-file", "off" } };
    for (const auto& [name, value] : changed) {
        INFO(name << " " << value);
        Shot other = shot;
        REQUIRE(set_shot_setting(other, name, value, error));
        CHECK(settings_hash(other, 1001) != hash);
    }
    Shot other = shot;
    other.inputs = { dir + "/other.#.exr" };
    CHECK(settings_hash(other, 1001) != hash);
    other = shot;
    REQUIRE(set_shot_setting(other, "frames", "1001-1040", error));
    REQUIRE(set_shot_setting(other, "memory-limit", "2G", error));
    CHECK(settings_hash(other, 1001) == hash);

    // The same shot from .dof files whose keys are in other orders, and
    // from relative paths, hashes the same.
    const std::string a = R"({"version": 1, "inputs": ["plate.#.exr"],
        "camera": {"focus": {"1001": 3, "1040": 1.2}, "fstop": 1.4},
        "aperture": {"shape": "polygon"}})";
    const std::string b = R"({"aperture": {"shape": "polygon"},
        "camera": {"fstop": 1.4, "focus": {"1040": 1.2, "1001": 3.0}},
        "inputs": ["plate.#.exr"], "version": 1})";
    Shot from_a, from_b;
    REQUIRE(parse_shot(a, dir, "a.dof", from_a, error));
    REQUIRE(parse_shot(b, dir, "b.dof", from_b, error));
    CHECK(settings_hash(from_a, 1001) == hash);
    CHECK(settings_hash(from_b, 1001) == hash);
}

TEST_CASE("an output is current only when it records the same settings hash")
{
    const std::string dir = scratch_dir("farm_current");
    std::string why;
    CHECK_FALSE(written_with_settings(dir + "/none.exr", "0123456789abcdef", why));
    CHECK(why == "does not exist");

    OIIO::ImageBuf image(OIIO::ImageSpec(4, 4, 4, OIIO::TypeFloat));
    std::string error;
    REQUIRE(write_image_atomic(image, dir + "/foreign.exr", OIIO::TypeHalf, "", error));
    CHECK_FALSE(written_with_settings(dir + "/foreign.exr", "0123456789abcdef", why));
    CHECK(OIIO::Strutil::contains(why, "no defocus:settingsHash"));

    image.specmod().attribute("defocus:settingsHash", "0123456789abcdef");
    REQUIRE(write_image_atomic(image, dir + "/ours.exr", OIIO::TypeHalf, "", error));
    CHECK(written_with_settings(dir + "/ours.exr", "0123456789abcdef", why));
    CHECK_FALSE(written_with_settings(dir + "/ours.exr", "fedcba9876543210", why));
    CHECK(OIIO::Strutil::contains(why, "other settings"));

    REQUIRE(OIIO::Filesystem::write_text_file(dir + "/broken.exr", "not an image"));
    CHECK_FALSE(written_with_settings(dir + "/broken.exr", "0123456789abcdef", why));
    CHECK(OIIO::Strutil::contains(why, "cannot be read"));
}

TEST_CASE("an output cut short is not current, whatever its header says")
{
    const std::string dir = scratch_dir("farm_incomplete");
    const std::string hash = "0123456789abcdef";
    OIIO::ImageBuf image(OIIO::ImageSpec(64, 64, 4, OIIO::TypeFloat));
    image.specmod().attribute("defocus:settingsHash", hash);
    std::string error, why;
    // Scanline and tiled EXRs (with every mipmap level), and a PNG.
    OIIO::ImageBuf tiled = image;
    tiled.specmod().tile_width = tiled.specmod().tile_height = 16;
    tiled.specmod().attribute("openexr:levelmode", 1);
    REQUIRE(write_image_atomic(image, dir + "/lines.exr", OIIO::TypeHalf, "none", error));
    REQUIRE(tiled.write(dir + "/tiles.exr"));
    REQUIRE(write_image_atomic(image, dir + "/image.png", OIIO::TypeUInt8, "", error));
    for (const std::string name : { "lines.exr", "tiles.exr", "image.png" }) {
        INFO(name);
        const std::string path = dir + "/" + name;
        REQUIRE(written_with_settings(path, hash, why));
        std::string bytes;
        REQUIRE(OIIO::Filesystem::read_text_file(path, bytes));
        // A task killed as it copied the frame, or a file system that lost
        // its end: the header is there, the last chunk is not whole. (An
        // EXR's chunks are checked against the file; a PNG ends with its
        // end marker; other formats are read whole.)
        for (size_t cut : { size_t(1), size_t(13), size_t(100) }) {
            REQUIRE(OIIO::Filesystem::write_text_file(path, bytes.substr(0, bytes.size() - cut)));
            CHECK_FALSE(written_with_settings(path, hash, why));
            CHECK(OIIO::Strutil::starts_with(why, "is incomplete ("));
        }
    }
}
