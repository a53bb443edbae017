// The readers alone, on file bytes: read as an image, any file gives a
// scene or a reason, its headers a size, and a frame that records the
// harness's settings hash is whole or says why not; read as a .dof, any
// file gives a shot or a reason. Never a crash, a hang or an allocation
// past the memory limit. Nothing is rendered, yet it runs about 50 inputs
// a second under ASan, as fuzz_scene does: the time goes to the zeroed
// memory OpenEXR's and LibRaw's readers allocate for what a header
// declares, not to defocus's own code.
#include <cstdint>
#include <string>

#include <unistd.h>

#include <OpenImageIO/filesystem.h>

#include <defocus/io/image_output.h>
#include <defocus/io/scene_io.h>
#include <defocus/shot/shot.h>
#include <defocus/io/shot_file.h>

#include "fuzz_check.h"

using namespace defocus;
using defocus_fuzz::require;

namespace {

/// The same bytes under both names: the scene readers and the .dof reader
/// go by what a file holds, the plugin by its extension. A seed .dof naming
/// "in.dof" or "in.exr" reaches itself or the image.
std::string image_file, shot_file;

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***)
{
    const std::string folder = OIIO::Strutil::fmt::format(
        "{}/defocus-fuzz-read-{}", OIIO::Filesystem::temp_directory_path(), getpid());
    OIIO::Filesystem::create_directory(folder);
    image_file = folder + "/in.exr";
    shot_file  = folder + "/in.dof";
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const std::string bytes(reinterpret_cast<const char*>(data), size);
    for (const std::string* file : { &image_file, &shot_file })
        require(OIIO::Filesystem::write_text_file(*file, bytes), "cannot write", *file);

    ReadOptions options;
    std::string error;
    require(MemoryLimit::parse("", "1G", options.memory_limit, error), "harness limit", error);
    OIIO::ImageSpec spec;
    if (!read_scene_spec({ image_file }, options, spec, error))
        defocus_fuzz::require_reason(error);
    Scene scene;
    if (!read_scene({ image_file }, options, scene, error))
        defocus_fuzz::require_reason(error);
    declared_bytes({ image_file }, options.memory_limit);
    // The seeds that record this hash reach the completeness check.
    std::string why;
    if (!written_with_settings(image_file, "00000000f022f022", why))
        defocus_fuzz::require_reason(why);

    Shot shot;
    if (!load_shot(shot_file, shot, error))
        defocus_fuzz::require_reason(error);
    return 0;
}
