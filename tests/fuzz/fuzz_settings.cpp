// Option values, keyframes and frame lists, as the command line, .dof files
// and plugin hints give them: each input is a few "NAME=VALUE" lines set on
// one shot, so that settings meet each other (frames with keyframes, focus
// with focus-at, ...).
#include <cstdint>
#include <string>
#include <vector>

#include <OpenImageIO/strutil.h>

#include <defocus/io/frames.h>
#include <defocus/shot/shot.h>

#include "fuzz_check.h"

using namespace defocus;
using defocus_fuzz::require;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const std::string text(reinterpret_cast<const char*>(data), size);
    Shot shot;
    std::string error;
    for (auto line : OIIO::Strutil::splits(text, "\n")) {
        const size_t equals = line.find('=');
        if (equals == std::string::npos)
            continue;
        const std::string name = line.substr(0, equals), value = line.substr(equals + 1);
        if (name == "input") {
            shot.inputs.push_back(value);
            continue;
        }
        if (!set_shot_setting(shot, name, value, error)) {
            defocus_fuzz::require_reason(error);
            continue;
        }
        // What a setting reads back as sets it to the same value.
        const std::string written = shot_setting(shot, name);
        Shot again = shot;
        require(set_shot_setting(again, name, written, error), "a setting does not read back:",
                name + "=" + written + ": " + error);
        require(shot_setting(again, name) == written, "a setting reads back changed:",
                name + "=" + written);
    }
    if (!check_shot(shot, error)) {
        defocus_fuzz::require_reason(error);
        return 0;
    }
    std::vector<int> frames;
    if (!shot_frames(shot, frames, error)) {
        defocus_fuzz::require_reason(error);
        return 0;
    }
    require(!frames.empty(), "a shot with no frames");
    for (int frame : { frames.front(), frames.back() }) {
        camera_at(shot, frame);
        frame_inputs(shot, frame);
    }
    return 0;
}
