// Fidelity on the path-traced garden scene (../shared/data/scenes/garden),
// scored with the metric in its README. Skips when the data is absent.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/strutil.h>

#include "test_support.h"

using namespace defocus_test;

namespace {

const int skip_status = 77;  // CTest's SKIP_RETURN_CODE for this test

double score(const std::string& input, double focus, const std::string& truth)
{
    const std::string garden = shared_data() + "/scenes/garden/";
    const std::string out = scratch_dir("garden") + "/out.exr";
    std::string log;
    const std::string command = OIIO::Strutil::fmt::format(
        "{} {}{} -o {} --focal 85 --fstop 1.4 --sensor 36 --focus {} --aperture box",
        DEFOCUS_BIN, garden, input, out, focus);
    REQUIRE(run(command, log) == 0);
    OIIO::ImageBuf result(out), reference(garden + truth);
    REQUIRE(result.read(0, 0, true, OIIO::TypeFloat));
    REQUIRE(reference.read(0, 0, true, OIIO::TypeFloat));
    return garden_psnr(result, reference);
}

}  // namespace

TEST_CASE("box aperture on layers.exr scores against the path-traced truths")
{
    const double focus3 = score("layers.exr", 3.0, "truth_focus3.exr");
    const double focus125 = score("layers.exr", 1.25, "truth_focus1.25.exr");
    WARN("garden layers.exr, box: " << focus3 << " dB at focus 3, " << focus125
                                    << " dB at focus 1.25");
    CHECK(focus3 >= 33.0);
    CHECK(focus125 >= 35.0);
}

int main(int argc, char* argv[])
{
    if (shared_data().empty()) {
        std::printf("SKIPPED: no shared data at %s (set DEFOCUS_SHARED_DATA)\n",
                    DEFOCUS_SHARED_DATA);
        return skip_status;
    }
    return Catch::Session().run(argc, argv);
}
