// One frame through the library, as every front end renders it: what is
// read, and what the frame's edges and depth units make of it.
#include <catch2/catch.hpp>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>

#include <defocus/render_frame.h>

#include "test_support.h"

using namespace defocus;
using namespace defocus_test;
using namespace OIIO;

namespace {

/// No overscan and, at 250 m, a 17 px CoC; at 2.5 m, 3.4 px.
const Settings close_up = { { "focal", "50" }, { "fstop", "1" }, { "focus", "2" },
                            { "sensor", "3.6" } };

Settings with(Settings more)
{
    more.insert(more.begin(), close_up.begin(), close_up.end());
    return more;
}

}  // namespace

TEST_CASE("a uniform field stays uniform to the corners without overscan")
{
    // The edges are extended by default (and the frame says so); with the
    // edge black the corners lose most of their light.
    const std::string field = scratch_dir("frame_edges") + "/field.exr";
    write_uniform_image(field, { "R", "G", "B", "A", "Z" }, { 0.5f, 0.5f, 0.5f, 1, 250 }, 48, 48);
    FrameResult result;
    std::string error;
    REQUIRE(render_with(field, close_up, result, error));
    CHECK(Strutil::contains(result.edges, "edges: layers extended up to"));
    const auto extended = ImageBufAlgo::computePixelStats(result.image);
    const auto black = ImageBufAlgo::computePixelStats(rendered(field, with({ { "edge", "black" } })));
    for (int c = 0; c < 4; ++c) {
        const float expected = c == 3 ? 1.0f : 0.5f;
        CHECK(extended.min[c] == Approx(expected).epsilon(1e-5));
        CHECK(extended.max[c] == Approx(expected).epsilon(1e-5));
    }
    CHECK(black.min[3] < 0.5f);
}

TEST_CASE("Z in other units than metres is read with the depth scale")
{
    // The same scene with Z in metres and in centimetres.
    const std::string dir = scratch_dir("frame_depth_scale");
    write_uniform_image(dir + "/m.exr", { "R", "G", "B", "A", "Z" }, { 1, 0.5f, 0.25f, 1, 2.5f },
                        48, 48);
    write_uniform_image(dir + "/cm.exr", { "R", "G", "B", "A", "Z" }, { 1, 0.5f, 0.25f, 1, 250 },
                        48, 48);
    const ImageBuf metres = rendered(dir + "/m.exr", with({ { "window", "grown" } }));
    const ImageBuf centimetres = rendered(
        dir + "/cm.exr", with({ { "window", "grown" }, { "depth-scale", "0.01" } }));
    const ImageBuf unscaled = rendered(dir + "/cm.exr", with({ { "window", "grown" } }));
    CHECK(ImageBufAlgo::compare(centimetres, metres, 1e-6f, 1e-6f).nfail == 0);
    CHECK(ImageBufAlgo::compare(unscaled, metres, 1e-3f, 1e-3f).nfail > 0);
}
