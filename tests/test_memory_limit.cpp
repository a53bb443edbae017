// The memory limit, through the library: what would pass it (a header's
// data window, deep samples, the cut into layers) is refused before it is
// allocated, with one line naming the file and the need.
#include <catch2/catch.hpp>

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>

#include <defocus/shot/shot.h>

#include "test_support.h"

using namespace defocus_test;
using namespace OIIO;

namespace {

/// The error of rendering frame 1 of `inputs` with `settings`, which must
/// be refused.
std::string refusal(const std::vector<std::string>& inputs, const Settings& settings)
{
    defocus::FrameResult result;
    std::string error;
    CHECK_FALSE(render_with(inputs, settings, result, error));
    return error;
}

/// True where `settings` render `inputs`.
bool renders(const std::vector<std::string>& inputs, const Settings& settings)
{
    defocus::FrameResult result;
    std::string error;
    const bool ok = render_with(inputs, settings, result, error);
    INFO(error);
    return ok && no_nan(result.image);
}

}  // namespace

TEST_CASE("a header asking for more memory than the limit is refused before allocating")
{
    const std::string dir = scratch_dir("memory_limit_header");
    // 200000 x 200000 pixels in a 100 KB file: 745 GB as RGBA + Z floats
    // to read (all a focus map does), and 1.16 TB more to spread into.
    const std::string giant = dir + "/giant.exr";
    write_exr_header_only(giant, 200000, 200000);
    CHECK(one_line_error(refusal({ giant }, { { "focus", "3" } }),
                          "giant.exr: spreading a data window of 200000x200000 needs 1.89 TB, "
                          "more than the memory limit of"));
    CHECK(one_line_error(refusal({ giant }, { { "focus", "3" }, { "output", "focusmap" } }),
                          "giant.exr: a data window of 200000x200000 needs 745 GB, more than "
                          "the memory limit of"));

    // The limit is the user's: a 20x20 scene needs 8 KB as a layer.
    const std::string scene = dir + "/small.exr";
    write_uniform_image(scene, { "R", "G", "B", "A", "Z" }, { 0.5f, 0.5f, 0.5f, 1.0f, 2.0f }, 20,
                        20);
    CHECK(renders({ scene }, { { "focus", "3" }, { "memory-limit", "1M" } }));
    const std::string big = dir + "/big.exr";
    write_exr_header_only(big, 4000, 3000);
    CHECK(one_line_error(refusal({ big }, { { "focus", "3" }, { "memory-limit", "100M" },
                                             { "output", "focusmap" } }),
                          "big.exr: a data window of 4000x3000 needs 229 MB, more than the "
                          "memory limit of 100 MB"));
    // Its layer would fit in 300 MB, but not beside the image it is spread
    // into and the accumulator: refused from the header too, before it is
    // read.
    CHECK(one_line_error(refusal({ big }, { { "focus", "3" }, { "memory-limit", "300M" } }),
                          "big.exr: spreading a data window of 4000x3000 needs 595 MB, more "
                          "than the memory limit of 300 MB"));
    // A strip of 3145731 x 16 pixels: 1 GB to read, 1.5 GB to spread into.
    // Counting only the latter, the header passed 2 GB and the file was
    // read (16 s under ASan) before the blur's estimate refused it. (Rows
    // 8388616 wide, as found, are refused sooner now: OpenEXR's buffers
    // for one chunk of 16 of them take 2.5 GB.)
    const std::string strip = dir + "/strip.exr";
    write_exr_header_only(strip, 3145731, 16);
    const std::string strip_refusal
        = refusal({ strip }, { { "focus", "3" }, { "memory-limit", "2G" } });
    INFO(strip_refusal);
    CHECK(one_line_error(strip_refusal,
                          "strip.exr: spreading a data window of 3145731x16 needs 2.44 GB, more "
                          "than the memory limit of 2 GB"));
    // Spreading: a blur of 20000 px grows every layer by 10000 px a side.
    CHECK(one_line_error(refusal({ scene }, { { "focus", "0.01" }, { "fstop", "0.1" },
                                               { "focal", "300" }, { "max-blur", "20000" },
                                               { "memory-limit", "1G" } }),
                          "with blur up to 20000 px needs"));
}

TEST_CASE("a memory limit is a size such as 12G")
{
    for (const char* bad : { "12X", "0.5K", "-1G", "G", "2P" }) {
        defocus::Shot shot;
        std::string error;
        CHECK_FALSE(defocus::set_shot_setting(shot, "memory-limit", bad, error));
        CHECK(one_line_error(error, "expected a size such as 12G"));
    }
    defocus::Shot shot;
    std::string error;
    CHECK(defocus::set_shot_setting(shot, "memory-limit", "1536M", error));
}

TEST_CASE("a deep pixel of two million samples renders, or is refused by the memory limit")
{
    const std::string dir = scratch_dir("memory_limit_deep_samples");
    ImageSpec spec = rgbaz_spec(2, 1);
    spec.deep = true;
    spec.attribute("compression", "zips");
    ImageBuf image(spec);
    DeepData& deep = *image.deepdata();
    const int samples = 2000000;
    deep.set_samples(0, samples);
    deep.set_samples(1, 1);
    for (int s = 0; s < samples; ++s) {
        deep.set_deep_value(0, 3, s, 1e-4f);
        deep.set_deep_value(0, 4, s, 1.0f + s * 1e-5f);
    }
    deep.set_deep_value(1, 3, 0, 1.0f);
    deep.set_deep_value(1, 4, 0, 2.0f);
    const std::string dense = dir + "/dense.exr", again = dir + "/again.exr";
    REQUIRE(image.write(dense));
    CHECK(renders({ dense }, { { "focus", "2" } }));
    CHECK(one_line_error(refusal({ dense }, { { "focus", "2" }, { "memory-limit", "32M" } }),
                          "dense.exr: 2000001 deep samples (up to 2000000 in one pixel) needs"));
    // The limit holds for the frame: one file fits in it (84 MB to read,
    // 48 MB kept, 122 MB to cut into layers), two do not, and the second
    // is refused before its samples are allocated (each file was checked
    // alone, and only cutting the merged samples found the limit passed).
    REQUIRE(Filesystem::copy(dense, again));
    CHECK(renders({ dense }, { { "focus", "2" }, { "memory-limit", "128M" } }));
    const std::string error = refusal({ dense, again }, { { "focus", "2" }, { "memory-limit", "128M" } });
    CHECK(one_line_error(error, "leaves beside the frame's other inputs"));
    CHECK(Strutil::contains(error, "again.exr: 2000001 deep samples"));
}

TEST_CASE("cutting into more layers than the memory limit holds is refused")
{
    const std::string dir = scratch_dir("memory_limit_layers");
    // Deep volume samples from 1 to 100 m: cut into 256 layers, each of
    // the 90000 samples becomes 256 fragments (830 MB), from a 1 MB file.
    ImageSpec spec(300, 300, 6, TypeFloat);
    spec.channelnames = { "R", "G", "B", "A", "Z", "ZBack" };
    spec.alpha_channel = 3;
    spec.z_channel = 4;
    ImageBuf flat(spec);
    const float fog[] = { 0.1f, 0.1f, 0.1f, 0.5f, 1.0f, 100.0f };
    ImageBufAlgo::fill(flat, fog);
    ImageBuf deep;
    REQUIRE(ImageBufAlgo::deepen(deep, flat));
    const std::string file = dir + "/fog.exr";
    REQUIRE(deep.write(file));
    const std::string error = refusal({ file }, { { "focus", "1" }, { "layers", "256" }, { "memory-limit", "256M" } });
    CHECK(one_line_error(error, "fog.exr: cutting 'deep0' into 256 layers needs"));
    CHECK(Strutil::contains(error, "more than the memory limit of 256 MB"));
    // The same cut in 8 layers fits.
    CHECK(renders({ file }, { { "focus", "1" }, { "layers", "8" }, { "memory-limit", "256M" } }));
}
