// Hostile and careless inputs to the library (round 3 of hostile testing):
// scene files and frame lists that must be refused, or read in linear time
// and give exactly what they name.
#include <catch2/catch.hpp>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>

#include <defocus/io/frames.h>
#include <defocus/shot/option_value.h>
#include <defocus/shot/shot.h>
#include <defocus/io/shot_file.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using OIIO::Strutil::contains;
using OIIO::Strutil::fmt::format;

namespace {

/// The frames a list names (`ok`), or why it names none.
struct FrameList {
    bool ok;
    std::vector<int> frames;
    std::string error;
};

FrameList frame_list(const std::string& list)
{
    Shot shot;
    shot.inputs = { "still.exr" };
    shot.frames = list;
    FrameList result;
    result.ok = shot_frames(shot, result.frames, result.error);
    return result;
}

std::vector<int> frames_of(const std::string& list)
{
    const FrameList result = frame_list(list);
    INFO(list << ": " << result.error);
    REQUIRE(result.ok);
    return result.frames;
}

std::string frames_error(const std::string& list)
{
    const FrameList result = frame_list(list);
    INFO(list);
    CHECK_FALSE(result.ok);
    return result.error;
}

}  // namespace

TEST_CASE("frame lists name what oiiotool's do, counted, never walked frame by frame")
{
    // The same frames, in the same order, as OpenImageIO's own reading.
    for (const char* list : { "1-10", "10-1", "1-10x3", "10-1x3", "1-10y3", "10-1y3", "-5--1",
                              "-1--5", "3", "1-1", "1-10x-3", "1-2x5", "5-5x2", "1-10x1",
                              "1,3,2", "0-4x2,1", "1001-1100y7", "-20-20x6" }) {
        std::vector<int> expected;
        REQUIRE(OIIO::Filesystem::enumerate_sequence(list, expected));
        CHECK(frames_of(list) == expected);
    }
    // A step of two billion names two frames; it used to be walked frame
    // by frame (3 s for one such range).
    CHECK(frames_of("1-2147483647x2147483646") == std::vector<int> { 1, 2147483647 });
    CHECK(frames_of("-1000000000-1000000000x1000000000")
          == std::vector<int> { -1000000000, 0, 1000000000 });
    CHECK(frames_of("1-5y1000000000") == std::vector<int> { 2, 3, 4, 5 });
    CHECK(contains(frames_error("1-2147483647y1000000000"), "at most 1000000"));
    CHECK(contains(frames_error("1-2147483647y1"), "names no frames"));
    // A frame listed twice would be rendered and written twice.
    CHECK(contains(frames_error("1,1,1"), "names frame 1 more than once"));
    CHECK(contains(frames_error("1-10,5-15"), "names frame 5 more than once"));
}

TEST_CASE("numbers are decimal: no hex floats, infinities or surrounding blanks")
{
    double value = 0;
    std::string error;
    for (const char* text : { "0x1p3", "0x10", "inf", "nan", " 3", "3 ", "1e999", "", "+", "3,5",
                              "--3", "+-3" }) {
        INFO(text);
        CHECK_FALSE(parse_number("--fstop", text, -1e9, 1e9, value, error));
        CHECK(contains(error, "is not a number"));
    }
    for (const auto& [text, expected] : std::vector<std::pair<const char*, double>> {
             { "3", 3.0 }, { "-2.5", -2.5 }, { "+0.01", 0.01 }, { "1e3", 1000.0 },
             { ".5", 0.5 }, { "5.", 5.0 } }) {
        INFO(text);
        REQUIRE(parse_number("--fstop", text, -1e9, 1e9, value, error));
        CHECK(value == expected);
    }
}

TEST_CASE(".dof files: keys given twice, NUL characters and version 0 are refused")
{
    const std::string dir = scratch_dir("hostile_dof");
    OIIO::Filesystem::write_text_file(dir + "/a.exr", "");
    const std::string head = "{\"version\": 1, \"inputs\": [\"a.exr\"], ";
    // The parser kept the last of two equal keys, silently.
    CHECK(contains(dof_error(head + "\"camera\": {\"fstop\": 2, \"fstop\": 4}}", dir),
                   "camera: the key 'fstop' is given twice"));
    CHECK(contains(dof_error(head + "\"camera\": {\"focus\": {\"1\": 2, \"1\": 3}}}", dir),
                   "camera.focus: the key '1' is given twice"));
    CHECK(contains(dof_error("{\"version\": 1, \"version\": 1, \"inputs\": [\"a.exr\"]}", dir),
                   "the key 'version' is given twice"));
    // A NUL cut the string short where it reached a C string.
    CHECK(contains(dof_error("{\"version\": 1, \"inputs\": [\"a.exr\\u0000.txt\"]}", dir),
                   "inputs: a string holds a NUL character"));
    CHECK(contains(dof_error(head + "\"color\": {\"input\": \"ACEScg\\u0000x\"}}", dir),
                   "color.input: a string holds a NUL character"));
    CHECK(contains(dof_error("{\"version\": 0, \"inputs\": [\"a.exr\"]}", dir),
                   "version: expected a whole number from 1"));
    CHECK(contains(dof_error(head + "\"camera\": {\"fstop\": \"0x1p3\"}}", dir),
                   "expected a number or keyframes"));
}

TEST_CASE(".dof files: a hundred thousand keyframes read back exactly, saved and read again")
{
    // Reading them was quadratic (200,000 keyframes: 19 s); the time is
    // measured by bench_speed ("scene file ..."), this checks the content.
    const std::string dir = scratch_dir("hostile_large_dof");
    OIIO::Filesystem::write_text_file(dir + "/a.exr", "");
    std::string keys;
    for (int frame = 1; frame <= 100000; ++frame)
        keys += format("{}\"{}\": {}", frame == 1 ? "" : ", ", frame, 1.0 + frame * 0.001);
    Shot shot;
    std::string error;
    REQUIRE(parse_shot(format("{{\"version\": 1, \"inputs\": [\"a.exr\"], \"camera\": "
                              "{{\"focus\": {{{}}}}}}}",
                              keys),
                       dir, "shot.dof", shot, error));
    REQUIRE(shot.focus.keys().size() == 100000);
    CHECK(shot.focus.at(77777, Interpolation::Linear)[0] == Approx(78.777));
    CHECK(shot.focus.keys().back().frame == 100000);

    Shot saved;
    REQUIRE(parse_shot(shot_to_json(shot, dir), dir, "saved.dof", saved, error));
    CHECK(shot_setting(saved, "focus") == shot_setting(shot, "focus"));
}
