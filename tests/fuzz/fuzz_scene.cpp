// The scene loader on file bytes: any file gives a rendered frame or a
// one-line reason, never a crash, a hang or an allocation past the memory
// limit; and a frame it renders holds no NaN or infinity.
#include <cmath>
#include <cstdint>
#include <string>

#include <unistd.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>

#include <defocus/io/shot_assets.h>
#include <defocus/render_frame.h>
#include <defocus/shot/shot.h>

#include "fuzz_check.h"

using namespace defocus;
using defocus_fuzz::require;

namespace {

std::string input_file;
Shot shot;
ShotAssets assets;

void set(const char* name, const char* value)
{
    std::string error;
    require(set_shot_setting(shot, name, value, error), "harness setting refused:", error);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***)
{
    input_file = OIIO::Strutil::fmt::format("{}/defocus-fuzz-{}.exr",
                                            OIIO::Filesystem::temp_directory_path(), getpid());
    shot.inputs = { input_file };
    set("focal", "50");
    set("fstop", "2");
    set("focus", "2");
    set("max-blur", "6");
    // What a header may ask for stays within libFuzzer's memory limit, so
    // that only an allocation the limit does not see is a finding.
    set("memory-limit", "1G");
    std::string error;
    require(read_shot_assets(shot, assets, error), "harness assets:", error);
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    {
        std::string bytes(reinterpret_cast<const char*>(data), size);
        require(OIIO::Filesystem::write_text_file(input_file, bytes), "cannot write",
                input_file);
    }
    FrameResult result;
    std::string error;
    if (!render_frame(shot, 1, assets, result, error, {}, 1)) {
        defocus_fuzz::require_reason(error);
        return 0;
    }
    const auto stats = OIIO::ImageBufAlgo::computePixelStats(result.image);
    for (size_t c = 0; c < stats.nancount.size(); ++c)
        require(stats.nancount[c] == 0 && stats.infcount[c] == 0, "NaN or inf written");
    return 0;
}
