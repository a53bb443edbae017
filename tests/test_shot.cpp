// Shots: keyframes, frame patterns, settings, .dof files and focusing on a
// pixel.
#include <filesystem>
#include <set>

#include <catch2/catch.hpp>

#include <Imath/ImathMatrix.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>

#include <defocus/error_line.h>
#include <defocus/focus/focus_at.h>
#include <defocus/io/aperture_files.h>
#include <defocus/io/frames.h>
#include <defocus/shot/keyframes.h>
#include <defocus/shot/shot.h>
#include <defocus/io/shot_file.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using OIIO::Strutil::contains;

namespace {

Keyframes parsed(const std::string& text, int arity = 1)
{
    Keyframes k;
    std::string error;
    INFO(text);
    REQUIRE(Keyframes::parse("--focus", text, arity, 1e-6, 1e30, k, error));
    return k;
}

std::string parse_error(const std::string& text, int arity = 1)
{
    Keyframes k;
    std::string error;
    CHECK_FALSE(Keyframes::parse("--focus", text, arity, 1e-6, 1e30, k, error));
    return error;
}

/// Every setting's text, to compare shots.
std::vector<std::string> settings_of(const Shot& shot)
{
    std::vector<std::string> all = shot.inputs;
    for (const ShotSetting& s : shot_settings())
        all.push_back(std::string(s.name) + "=" + shot_setting(shot, s.name));
    return all;
}

}  // namespace

TEST_CASE("keyframes: constants, and focus pulls linear in 1/z")
{
    const Keyframes constant = parsed("2.5");
    CHECK_FALSE(constant.animated());
    CHECK(constant.at(-100, Interpolation::Reciprocal)[0] == 2.5);
    CHECK(constant.to_string() == "2.5");

    const Keyframes pull = parsed("1001:3,1040:1.2,1100:1.2");
    CHECK(pull.animated());
    CHECK(pull.at(900, Interpolation::Reciprocal)[0] == 3.0);  // the end keys hold
    CHECK(pull.at(1001, Interpolation::Reciprocal)[0] == 3.0);
    CHECK(pull.at(1070, Interpolation::Reciprocal)[0] == Approx(1.2));
    CHECK(pull.at(2000, Interpolation::Reciprocal)[0] == 1.2);
    // Halfway in frames is halfway in 1/z, so the CoC moves at an even rate.
    const double mid = pull.at(1020.5, Interpolation::Reciprocal)[0];
    CHECK(1.0 / mid == Approx(0.5 * (1.0 / 3.0 + 1.0 / 1.2)));
    CHECK(pull.at(1020.5, Interpolation::Linear)[0] == Approx(2.1));
    CHECK(pull.to_string() == "1001:3,1040:1.2,1100:1.2");

    const Keyframes at = parsed("1:100,50,11:200,150", 2);
    CHECK(at.at(6, Interpolation::Linear) == Keyframes::Value { 150.0, 100.0 });
    CHECK(parsed("640,360", 2).at(3, Interpolation::Linear) == Keyframes::Value { 640, 360 });

    CHECK(contains(parse_error("1:3,1:4"), "must increase"));
    CHECK(contains(parse_error("5:3,2:4"), "must increase"));
    CHECK(contains(parse_error("1:3,4"), "--focus"));
    CHECK(contains(parse_error("1.5:3"), "whole number"));
    CHECK(contains(parse_error("1:-2"), "out of range"));
    CHECK(contains(parse_error("far"), "not a number"));
    CHECK(contains(parse_error(""), "--focus"));
    CHECK(contains(parse_error("640", 2), "X,Y"));
}

TEST_CASE("frame patterns in oiiotool's syntax")
{
    CHECK(is_frame_pattern("shot.#.exr"));
    CHECK(is_frame_pattern("shot.@@.exr"));
    CHECK(is_frame_pattern("shot.%03d.exr"));
    CHECK(is_frame_pattern("shot.1-10#.exr"));
    CHECK_FALSE(is_frame_pattern("shot.0001.exr"));
    CHECK(frame_path("shot.#.exr", 7) == "shot.0007.exr");
    CHECK(frame_path("shot.@@.exr", 7) == "shot.07.exr");
    CHECK(frame_path("shot.%03d.exr", 1001) == "shot.1001.exr");
    CHECK(frame_path("dir/shot.exr", 7) == "dir/shot.exr");

    Shot shot;
    std::vector<int> frames;
    std::string error;
    shot.inputs = { "still.exr" };
    shot.focus  = Keyframes(3.0);
    REQUIRE(shot_frames(shot, frames, error));
    CHECK(frames == std::vector<int> { 1 });
    CHECK_FALSE(is_sequence(shot));

    shot.frames = "1-9x4,20,12-10";
    REQUIRE(shot_frames(shot, frames, error));
    CHECK(frames == std::vector<int> { 1, 5, 9, 20, 12, 11, 10 });
    shot.frames = "1-";
    CHECK_FALSE(shot_frames(shot, frames, error));
    CHECK(contains(command_line_words(error), "--frames"));

    // Without a list, an embedded range, else the files on disk.
    const std::string dir = scratch_dir("shot_frames");
    for (int f : { 3, 4, 6 })
        OIIO::Filesystem::write_text_file(dir + "/seq." + std::to_string(f) + ".exr", "");
    shot.frames = "";
    shot.inputs = { dir + "/seq.@.exr" };
    // A gap among them is a missing frame, not one frame less.
    CHECK_FALSE(shot_frames(shot, frames, error));
    CHECK(contains(error, dir + "/seq.5.exr: no such file; frames with input files missing: 5"));
    std::vector<int> missing;
    REQUIRE(set_shot_setting(shot, "missing-frames", "skip", error));
    REQUIRE(shot_frames(shot, frames, error, &missing));
    CHECK(frames == std::vector<int> { 3, 4, 6 });
    CHECK(missing == std::vector<int> { 5 });
    REQUIRE(set_shot_setting(shot, "missing-frames", "hold", error));
    REQUIRE(shot_frames(shot, frames, error));
    CHECK(frames == std::vector<int> { 3, 4, 5, 6 });
    CHECK(frame_inputs(shot, 5) == std::vector<std::string> { dir + "/seq.4.exr" });
    CHECK(frame_inputs(shot, 6) == std::vector<std::string> { dir + "/seq.6.exr" });
    shot.inputs = { dir + "/seq.3-4@.exr" };
    REQUIRE(shot_frames(shot, frames, error));
    CHECK(frames == std::vector<int> { 3, 4 });
    shot.missing_frames = MissingFrames::Error;
    shot.inputs = { dir + "/none.#.exr" };
    CHECK_FALSE(shot_frames(shot, frames, error));
    CHECK(contains(error, "no files match"));
    // '#' is four digits: one-digit files get a hint at '@'.
    shot.inputs = { dir + "/seq.#.exr" };
    CHECK_FALSE(shot_frames(shot, frames, error));
    CHECK(one_line_error(error, dir + "/seq.#.exr: no files match, but " + dir
                                    + "/seq.@.exr matches 3 (seq.3.exr to seq.6.exr)"));

    // Keyframes on a still need frames to be taken at.
    shot.inputs = { "still.exr" };
    REQUIRE(set_shot_setting(shot, "focus", "1:1.25,24:3", error));
    CHECK_FALSE(shot_frames(shot, frames, error));
    CHECK(contains(command_line_words(error), "--frames"));
}

TEST_CASE("a frame is missing exactly when no entry has the name its pattern writes")
{
    // The folder is listed once per pattern rather than each frame's file
    // looked up: the listing must agree with the lookup name by name.
    const std::string dir = scratch_dir("frames_on_disk");
    for (const char* name : { "seq.0001.exr", "seq.02.exr", "seq.00003.exr", "seq.12345.exr",
                              "seq.-001.exr", "seq.1234567890.exr", "seq.0006.exr.tmp",
                              "xseq.0007.exr", "seq.-0002.exr", "seq.-3.exr", "seq.+008.exr",
                              "seq.-99999999999.exr" })
        OIIO::Filesystem::write_text_file(dir + "/" + name, "");
    std::filesystem::create_symlink(dir + "/nowhere", dir + "/seq.0004.exr");
    OIIO::Filesystem::create_directory(dir + "/seq.0005.exr");
    OIIO::Filesystem::create_directory(dir + "/take.0008");
    OIIO::Filesystem::write_text_file(dir + "/take.0008/seq.exr", "");
    OIIO::Filesystem::create_directory(dir + "/take.0009");  // no seq.exr
    OIIO::Filesystem::create_directory(dir + "/take.00010");  // not as %04d writes 10
    OIIO::Filesystem::write_text_file(dir + "/take.00010/seq.exr", "");

    Shot shot;
    std::string error;
    std::vector<int> frames, missing;
    shot.focus = Keyframes(3.0);
    REQUIRE(set_shot_setting(shot, "missing-frames", "skip", error));
    // Negative frames too (a million of them were a million lookups): "%04d"
    // writes -2 as "-002", and no frame as "+008".
    shot.frames = "-3--1,1-8,12345,1234567890";
    shot.inputs = { dir + "/seq.#.exr" };
    REQUIRE(shot_frames(shot, frames, error, &missing));
    CHECK(frames == std::vector<int> { -1, 1, 4, 5, 12345, 1234567890 });
    CHECK(missing == std::vector<int> { -3, -2, 2, 3, 6, 7, 8 });

    // The frame number in a folder's name: the folders are listed, and the
    // file looked up in those that are there.
    shot.frames = "7-10";
    shot.inputs = { dir + "/take.#/seq.exr" };
    REQUIRE(shot_frames(shot, frames, error, &missing));
    CHECK(frames == std::vector<int> { 8 });
    CHECK(missing == std::vector<int> { 7, 9, 10 });
}

TEST_CASE("shot settings: command-line text, errors, focus and focus-at exclude each other")
{
    Shot shot;
    std::string error;
    REQUIRE(set_shot_setting(shot, "focus", "3", error));
    REQUIRE(set_shot_setting(shot, "aperture", "mask:iris.png", error));
    CHECK(shot.spread.aperture.shape == ApertureShape::Mask);
    CHECK(shot.spread.aperture.mask_file == "iris.png");
    REQUIRE(set_shot_setting(shot, "focus-at", "10,20", error));
    CHECK(shot.focus.empty());
    REQUIRE(set_shot_setting(shot, "focus", "2", error));
    CHECK(shot.focus_at.empty());
    REQUIRE(set_shot_setting(shot, "pixel-type", "half", error));
    CHECK(shot.pixel_type == OIIO::TypeHalf);

    CHECK_FALSE(set_shot_setting(shot, "blades", "2", error));
    CHECK(contains(command_line_words(error), "--blades"));
    CHECK_FALSE(set_shot_setting(shot, "blades", "6.5", error));
    CHECK(contains(error, "whole number"));
    CHECK_FALSE(set_shot_setting(shot, "lens", "fisheye", error, "camera.lens"));
    CHECK(contains(error, "camera.lens: unknown model 'fisheye'"));
    CHECK_FALSE(set_shot_setting(shot, "pixel-type", "int8", error, "-d"));
    CHECK(contains(error, "-d: unknown type"));
    CHECK_FALSE(set_shot_setting(shot, "window", "huge", error));
    CHECK_FALSE(set_shot_setting(shot, "fcous", "3", error));
    CHECK(contains(error, "unknown setting 'fcous'"));

    const Camera camera = camera_at(shot, 1);
    CHECK(camera.focus_distance == 2.0);
    CHECK(camera.fstop == 2.8);  // the defaults
    CHECK(camera.focal_length_mm == 50.0);
}

TEST_CASE("every setting but the mask file is on the command line, with help")
{
    for (const ShotSetting& s : shot_settings()) {
        INFO(s.name);
        // The mask's file is given with its shape: --aperture mask:FILE.
        CHECK((s.option || !s.switches.empty()) == (std::string(s.name) != "aperture-mask"));
        CHECK(std::string(s.help).size() > 10);
        for (const SettingSwitch& on : s.switches) {
            Shot shot;
            std::string error;
            CHECK(set_shot_setting(shot, s.name, on.value, error));
        }
    }
}

TEST_CASE("checking a shot reads no file, and the images its aperture names are read apart")
{
    Shot shot;
    shot.inputs = { "scene.exr" };
    std::string error;
    REQUIRE(set_shot_setting(shot, "focus", "3", error));
    const std::string dir = scratch_dir("aperture_images");
    REQUIRE(set_shot_setting(shot, "aperture", "mask:" + dir + "/no_mask.png", error));
    REQUIRE(set_shot_setting(shot, "psf-image", dir + "/no_psf.exr", error));
    CHECK(check_shot(shot, error));

    ApertureImages images;
    CHECK_FALSE(read_aperture_images(shot, luma_weights(nullptr), images, error));
    CHECK(contains(command_line_words(error), "--aperture: "));
    CHECK(contains(error, "no_mask.png: cannot read the aperture mask"));

    ImageBuf mask = zero_image(ROI(0, 8, 0, 8), 1);
    const float one = 1.0f;
    mask.setpixel(4, 4, &one);
    REQUIRE(mask.write(dir + "/mask.exr"));
    REQUIRE(set_shot_setting(shot, "aperture", "mask:" + dir + "/mask.exr", error));
    CHECK_FALSE(read_aperture_images(shot, luma_weights(nullptr), images, error));
    CHECK(contains(command_line_words(error), "--psf-image: "));
    CHECK(contains(error, "no_psf.exr: cannot read the PSF image"));

    REQUIRE(set_shot_setting(shot, "psf-image", "", error));
    INFO(error);
    REQUIRE(read_aperture_images(shot, luma_weights(nullptr), images, error));
    CHECK(images.mask);
    CHECK_FALSE(images.psf);
}

TEST_CASE(".dof files: every setting round-trips, paths relative to the file")
{
    const std::string dir = scratch_dir("shot_file");
    OIIO::Filesystem::create_directory(dir + "/plates");
    OIIO::Filesystem::write_text_file(dir + "/plates/a.exr", "");
    Shot shot;
    shot.inputs = { dir + "/plates/a.exr", dir + "/plates/b.#.exr" };
    std::string error;
    for (const auto& [name, value] :
         std::vector<std::pair<std::string, std::string>> {
             { "frames", "1-24" }, { "view", "left" }, { "layer", "beauty" },
             { "layers", "12" }, { "depth-kind", "inverse" }, { "focus", "1:1.25,24:3" },
             { "focal", "85" },
             { "fstop", "1:1.4,24:2.8" }, { "sensor", "24.89" }, { "lens", "optical" },
             { "max-blur", "100" }, { "aperture", "polygon" }, { "blades", "7" },
             { "rotation", "15" }, { "roundness", "0.25" }, { "aspect", "0.5" },
             { "hybrid-threshold", "6" }, { "aperture-cells", "25" },
             { "iscolorspace", "ACEScg" }, { "bloom", "1:0.9,4,24:0.8,6" },
             { "tocolorspace", "srgb_tx" }, { "output", "focusmap" },
             { "pixel-type", "float" }, { "compression", "dwaa" }, { "window", "grown" },
             { "memory-limit", "1536M" } })
        REQUIRE(set_shot_setting(shot, name, value, error));
    REQUIRE(save_shot(shot, dir + "/shot.dof", error));

    std::string text;
    REQUIRE(OIIO::Filesystem::read_text_file(dir + "/shot.dof", text));
    CHECK(contains(text, "\"plates/a.exr\""));  // relative: the folder can move
    CHECK(contains(text, "\"focus\": {"));
    CHECK(contains(text, "\"version\": 1"));

    Shot loaded;
    REQUIRE(load_shot(dir + "/shot.dof", loaded, error));
    CHECK(settings_of(loaded) == settings_of(shot));

    // Focusing at a pixel, keyframed: points in JSON.
    REQUIRE(set_shot_setting(shot, "focus-at", "1:10,20,24:30.5,40", error));
    const std::string with_points = shot_to_json(shot, dir);
    CHECK(contains(with_points, "\"focus_at\": {"));
    CHECK(contains(with_points, "30.5,"));
    Shot pointed;
    REQUIRE(parse_shot(with_points, dir, "shot.dof", pointed, error));
    CHECK(settings_of(pointed) == settings_of(shot));
    CHECK(pointed.focus.empty());

    // Loading from elsewhere resolves paths against the file's folder.
    Shot again;
    REQUIRE(parse_shot(text, dir, "shot.dof", again, error));
    CHECK(again.inputs.front() == dir + "/plates/a.exr");
}

TEST_CASE(".dof files: one-line errors for bad JSON, keys, types, values and files")
{
    const std::string dir = scratch_dir("shot_file_errors");
    OIIO::Filesystem::write_text_file(dir + "/a.exr", "");
    const std::string head = "{\"version\": 1, \"inputs\": [\"a.exr\"], ";
    CHECK(contains(dof_error("{\"version\": 1,\n \"inputs\": [\"a.exr\"}", dir),
                   "not valid JSON: parse error at line 2"));
    CHECK(contains(dof_error("[1, 2]", dir), "expected a JSON object"));
    CHECK(contains(dof_error("{\"inputs\": [\"a.exr\"]}", dir), "no \"version\""));
    CHECK(contains(dof_error("{\"version\": 9, \"inputs\": [\"a.exr\"]}", dir), "newer"));
    CHECK(contains(dof_error("{\"version\": 1}", dir), "no \"inputs\""));
    CHECK(contains(dof_error("{\"version\": 1, \"inputs\": [\"b.exr\"]}", dir),
                   "b.exr: no such file"));
    CHECK(contains(dof_error("{\"version\": 1, \"inputs\": \"a.exr\"}", dir),
                   "inputs: expected a list"));
    CHECK(contains(dof_error("{\"version\": 1, \"inputs\": []}", dir),
                   "inputs: the list is empty"));
    CHECK(contains(dof_error(head + "\"camra\": {}}", dir), "unknown key 'camra'"));
    CHECK(contains(dof_error(head + "\"camera\": {\"fcous\": 3}}", dir),
                   "unknown key 'camera.fcous'"));
    CHECK(contains(dof_error(head + "\"camera\": {\"focus\": \"3\"}}", dir),
                   "camera.focus: expected a number or keyframes"));
    CHECK(contains(dof_error(head + "\"camera\": {\"focus\": {\"one\": 3}}}", dir),
                   "camera.focus: key 'one' is not a frame number"));
    CHECK(contains(dof_error(head + "\"camera\": {\"focus_at\": [1]}}", dir),
                   "camera.focus_at: expected [x, y]"));
    CHECK(contains(dof_error(head + "\"camera\": {\"fstop\": -2}}", dir),
                   "camera.fstop: -2 is out of range"));
    CHECK(contains(dof_error(head + "\"camera\": {\"focus\": 3, \"focus_at\": [1, 2]}}", dir),
                   "not both"));
    CHECK(contains(dof_error(head + "\"aperture\": {\"blades\": 4.5}}", dir),
                   "aperture.blades: 4.5 is not a whole number"));
    CHECK(contains(dof_error(head + "\"output\": []}", dir), "output: expected an object"));
    // Found by fuzzing-style probes: numbers out of a double's range, and
    // a version that a narrower integer would wrap round to 1.
    CHECK(contains(dof_error(head + "\"camera\": {\"focus\": 96e379}}", dir),
                   "not valid JSON: number overflow"));
    CHECK(contains(dof_error("99e999", dir), "not valid JSON: number overflow"));
    CHECK(contains(dof_error("{\"version\": 4294967297, \"inputs\": [\"a.exr\"]}", dir),
                   "version 4294967297 is newer"));
    CHECK(contains(dof_error("{\"version\": -3, \"inputs\": [\"a.exr\"]}", dir),
                   "version: expected a whole number from 1"));

    Shot shot;
    std::string error;
    CHECK_FALSE(load_shot(dir + "/missing.dof", shot, error));
    CHECK(error == dir + "/missing.dof: no such file");
}

TEST_CASE("focus-at: the median depth of the front-most opaque surface")
{
    // A 20x20 display window: a far wall at 8 m, a half-transparent veil at
    // 1 m over all of it, and an opaque post at 2 m over columns 8..12
    // with one stray pixel at 30 m.
    Scene scene;
    scene.spec = OIIO::ImageSpec(20, 20, 4, OIIO::TypeFloat);
    auto layer = [&](float z, float alpha, ROI roi) {
        Layer l;
        l.color = zero_image(roi, 4);
        l.depth = zero_image(roi, 1);
        const float rgba[4] = { alpha, alpha, alpha, alpha };
        OIIO::ImageBufAlgo::fill(l.color, rgba);
        OIIO::ImageBufAlgo::fill(l.depth, { z });
        return l;
    };
    scene.layers.push_back(layer(8.0f, 1.0f, ROI(0, 20, 0, 20)));
    scene.layers.push_back(layer(1.0f, 0.4f, ROI(0, 20, 0, 20)));
    scene.layers.push_back(layer(2.0f, 1.0f, ROI(8, 13, 0, 20)));
    OIIO::ImageBufAlgo::fill(scene.layers[2].depth, { 30.0f }, ROI(10, 11, 10, 11));

    double distance = 0;
    std::string error;
    REQUIRE(focus_distance_at(scene, 10, 10, distance, error));
    CHECK(distance == 2.0);  // the veil is not opaque; the stray pixel is outvoted
    // A shot's --focus-at-radius 0 looks at the pixel alone, where the
    // stray 30 m puts the post behind the wall: the wall is seen.
    Shot shot;
    REQUIRE(set_shot_setting(shot, "focus-at", "10,10", error));
    REQUIRE(set_shot_setting(shot, "focus-at-radius", "0", error));
    Camera camera;
    CameraOrigins origins;
    REQUIRE(shot_camera(shot, scene, 1, camera, origins, error));
    CHECK(camera.focus_distance == 8.0);
    REQUIRE(set_shot_setting(shot, "focus-at-radius", "2", error));
    REQUIRE(shot_camera(shot, scene, 1, camera, origins, error));
    CHECK(camera.focus_distance == 2.0);
    REQUIRE(focus_distance_at(scene, 2, 3, distance, error));
    CHECK(distance == 8.0);
    scene.layers[1] = layer(1.0f, 0.6f, ROI(0, 20, 0, 20));
    REQUIRE(focus_distance_at(scene, 2, 3, distance, error));
    CHECK(distance == 1.0);  // now the veil is

    CHECK_FALSE(focus_distance_at(scene, 25, 3, distance, error));
    CHECK(contains(error, "outside the 20x20 display window"));
    scene.layers.clear();
    CHECK_FALSE(focus_distance_at(scene, 2, 3, distance, error));
    CHECK(contains(error, "nothing opaque"));
}

TEST_CASE("the camera a render recorded: read from its header unless given, and said where from")
{
    OIIO::ImageSpec header(20, 20, 4, OIIO::TypeFloat);
    // OpenEXR's standard attributes (OpenImageIO names `aperture` FNumber),
    // Unreal's strings in cm and mm, Arnold's focal length.
    header.attribute("focus", 3.5f);
    header.attribute("FNumber", 2.0f);
    header.attribute("unreal/camera/FinalImage/focalDistance", "250.0");
    header.attribute("unreal/camera/FinalImage/sensorWidth", "24.89");
    header.attribute("CameraFocalLength", 35.0f);
    const HeaderCamera found = camera_from_header(header);
    CHECK(found.focus_distance.value == Approx(3.5));
    CHECK(found.focus_distance.attribute == "focus");
    CHECK(found.fstop.value == Approx(2.0));
    CHECK(found.focal_length_mm.value == Approx(35.0));
    CHECK(found.sensor_width_mm.value == Approx(24.89));
    CHECK(found.sensor_width_mm.attribute == "unreal/camera/FinalImage/sensorWidth");

    // Unreal alone: any pass, centimetres to metres; nonsense is ignored.
    OIIO::ImageSpec unreal(20, 20, 4, OIIO::TypeFloat);
    unreal.attribute("unreal/camera/Beauty/focalDistance", "250.0");
    unreal.attribute("unreal/camera/Beauty/fstop", "not a number");
    unreal.attribute("unreal/camera/Beauty/focalLength", "-5");
    const HeaderCamera from_unreal = camera_from_header(unreal);
    CHECK(from_unreal.focus_distance.value == Approx(2.5));
    CHECK_FALSE(from_unreal.fstop.found());
    CHECK_FALSE(from_unreal.focal_length_mm.found());

    Scene scene;
    scene.spec = header;
    Shot shot;
    std::string error;
    REQUIRE(set_shot_setting(shot, "fstop", "1.4", error, "--fstop"));
    Camera camera;
    CameraOrigins origins;
    REQUIRE(shot_camera(shot, scene, 1, camera, origins, error));
    CHECK(camera.focus_distance == Approx(3.5));
    CHECK(camera.fstop == Approx(1.4));  // given: the flag wins
    CHECK(camera.focal_length_mm == Approx(35.0));
    CHECK(camera.sensor_width_mm == Approx(24.89));
    CHECK(origins.focus == "file: focus");
    CHECK(origins.fstop == "--fstop");
    CHECK(origins.focal_length == "file: CameraFocalLength");

    // A render's projection gives f/s: with its focal length, the filmback.
    OIIO::ImageSpec projected(20, 20, 4, OIIO::TypeFloat);
    projected.attribute("CameraFocalLength", 35.0f);
    Imath::M44f world_to_camera;
    world_to_camera.setTranslation(Imath::V3f(1.0f, 2.0f, 3.0f));
    const float a = 35.0f / 24.89f;  // x_ndc = (f/s) x / z + 1/2
    Imath::M44f camera_to_ndc(a, 0, 0, 0, 0, -a * 16.0f / 9.0f, 0, 0, 0.5f, 0.5f, 1, 1, 0, 0, 0, 0);
    const Imath::M44f world_to_ndc = world_to_camera * camera_to_ndc;
    projected.attribute("worldToCamera", OIIO::TypeMatrix44, &world_to_camera);
    projected.attribute("worldToNDC", OIIO::TypeMatrix44, &world_to_ndc);
    projected.attribute("focus", 2.0f);
    scene.spec = projected;
    Shot plain;
    REQUIRE(shot_camera(plain, scene, 1, camera, origins, error));
    CHECK(camera.sensor_width_mm == Approx(24.89).epsilon(1e-5));
    CHECK(origins.sensor_width == "file: worldToNDC and the focal length");
    // Without a focal length from the file, the ratio alone says nothing.
    projected.erase_attribute("CameraFocalLength");
    scene.spec = projected;
    REQUIRE(shot_camera(plain, scene, 1, camera, origins, error));
    CHECK(camera.sensor_width_mm == Camera().sensor_width_mm);
    scene.spec = header;

    // Off: nothing is read, and without a focus the frame is an error.
    REQUIRE(set_shot_setting(shot, "camera-from-file", "off", error));
    CHECK_FALSE(shot_camera(shot, scene, 1, camera, origins, error));
    CHECK(contains(error, "no focus distance"));
    REQUIRE(set_shot_setting(shot, "focus", "2", error));
    REQUIRE(shot_camera(shot, scene, 1, camera, origins, error));
    CHECK(camera.focal_length_mm == Camera().focal_length_mm);
    CHECK(origins.focal_length == "default");
    CHECK(in_words(origins.focus, SettingForm::CommandLine) == "--focus");
}

TEST_CASE("error lines: control characters escaped, overlong messages cut in the middle")
{
    CHECK(error_line("shot.dof: unknown key 'a\nb\tc\x01'", SettingForm::SceneFile)
          == "shot.dof: unknown key 'a\\nb\\tc\\x01'");
    const std::string huge = "shot.dof: unknown key '" + std::string(100000, 'k') + "'";
    const std::string line = error_line(huge, SettingForm::SceneFile, 200);
    CHECK(line.size() <= 200);
    CHECK(OIIO::Strutil::starts_with(line, "shot.dof: unknown key 'kkk"));
    CHECK(OIIO::Strutil::ends_with(line, "kkk'"));
    CHECK(contains(line, " ... "));
    CHECK(error_line("short", SettingForm::SceneFile) == "short");
}

TEST_CASE("a library message names settings as each front end writes them")
{
    const std::string message =
        "give " + mention("focus-at", "X,Y") + " or " + mention("focus-at", "10,20") + "; "
        + mention("window", "display") + ", " + mention("pixel-type", "half") + ", "
        + mention("camera-from-file", "off") + ", " + mention("memory-limit");
    CHECK(error_line(message, SettingForm::CommandLine)
          == "give --focus-at X,Y or --focus-at 10,20; --crop, -d half, --camera-from-file off, "
             "--memory-limit");
    CHECK(error_line(message, SettingForm::Python)
          == "give focus_at=X,Y or focus_at=(10, 20); window=\"display\", pixel_type=\"half\", "
             "camera_from_file=False, memory_limit");
    CHECK(error_line(message, SettingForm::SceneFile)
          == "give camera.focus_at X,Y or camera.focus_at [10, 20]; output.window \"display\", "
             "output.type \"half\", camera.from_file \"off\", scene.memory_limit");
    // A file name holding the marks stays visible.
    CHECK(error_line("a\x1f" "b.exr: no such file", SettingForm::Python)
          == "a\\x1fb.exr: no such file");
}

TEST_CASE("an error passed up through scene files names each file once")
{
    CHECK(error_about("a.dof", "no focus") == "a.dof: no focus");
    CHECK(error_about("a.dof", "a.dof: no focus") == "a.dof: no focus");
    CHECK(error_about("a.dof", "b.dof: no focus") == "a.dof: b.dof: no focus");
    CHECK(error_about("a.dof", "a.dofx: no focus") == "a.dof: a.dofx: no focus");
}
