// The .dof parser: any text gives a shot or a reason, never a crash, and a
// shot it accepts writes back to a .dof that reads as the same shot.
#include <cstdint>
#include <string>

#include <OpenImageIO/filesystem.h>

#include <defocus/shot/shot.h>
#include <defocus/io/shot_file.h>

#include "fuzz_check.h"

using namespace defocus;
using defocus_fuzz::require;

namespace {

/// A folder holding the files the seed .dofs name (scene.exr, psf.exr), so
/// that inputs and paths can resolve.
std::string scene_directory;

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***)
{
    scene_directory = OIIO::Filesystem::temp_directory_path() + "/defocus-fuzz-dof";
    OIIO::Filesystem::create_directory(scene_directory);
    for (const char* name : { "scene.exr", "psf.exr" }) {
        std::string ignored;
        OIIO::Filesystem::write_text_file(scene_directory + "/" + name, ignored);
    }
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const std::string text(reinterpret_cast<const char*>(data), size);
    Shot shot;
    std::string error;
    if (!parse_shot(text, scene_directory, "fuzz.dof", shot, error)) {
        defocus_fuzz::require_reason(error);
        return 0;
    }
    const std::string saved = shot_to_json(shot, scene_directory);
    Shot reread;
    require(parse_shot(saved, scene_directory, "saved.dof", reread, error),
            "a saved shot does not read back:", error + "\n" + saved);
    require(shot_to_json(reread, scene_directory) == saved, "a saved shot reads back changed:",
            saved);
    if (!check_shot(shot, error))
        defocus_fuzz::require_reason(error);
    return 0;
}
