// Zip-compressed outputs deflated by libdeflate: zlib's compress2 contract
// kept (utils/zlib_compress.cpp, linked into this test too), and the tools'
// OpenEXR writes bound to it.
#include <catch2/catch.hpp>

#include <zlib.h>

#include <random>
#include <vector>

#include <libdeflate.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>

#include "test_support.h"

using namespace defocus_test;
using namespace OIIO;

namespace {

/// Half noise, half a repeating ramp: some of it compresses, some not.
std::vector<Bytef> mixed_bytes(size_t n)
{
    std::vector<Bytef> bytes(n);
    std::mt19937 random(7);
    for (size_t i = 0; i < n; ++i)
        bytes[i] = i < n / 2 ? Bytef(random()) : Bytef(i % 61);
    return bytes;
}

std::vector<Bytef> inflated(const std::vector<Bytef>& stream, size_t size)
{
    std::vector<Bytef> out(size);
    uLongf out_size = size;
    REQUIRE(uncompress(out.data(), &out_size, stream.data(), stream.size()) == Z_OK);
    out.resize(out_size);
    return out;
}

}  // namespace

TEST_CASE("compress2 keeps zlib's contract at every level, with libdeflate's streams")
{
    const std::vector<Bytef> source = mixed_bytes(1 << 20);
    for (int level : { Z_DEFAULT_COMPRESSION, 0, 1, 4, 6, 9 }) {
        INFO("level " << level);
        std::vector<Bytef> stream(compressBound(source.size()));
        uLongf size = stream.size();
        REQUIRE(compress2(stream.data(), &size, source.data(), source.size(), level) == Z_OK);
        stream.resize(size);
        CHECK(inflated(stream, source.size()) == source);
        if (level > 0) {  // the same bytes libdeflate writes: it, not zlib, deflated them
            libdeflate_compressor* c = libdeflate_alloc_compressor(level);
            std::vector<Bytef> expected(stream.size() + 1024);
            expected.resize(libdeflate_zlib_compress(c, source.data(), source.size(),
                                                     expected.data(), expected.size()));
            libdeflate_free_compressor(c);
            CHECK(stream == expected);
        }
    }
    uLongf size = compressBound(source.size());
    std::vector<Bytef> stream(size);
    CHECK(compress(stream.data(), &size, source.data(), source.size()) == Z_OK);
    CHECK(size < source.size());

    // Too little room, and levels zlib does not know, fail as zlib fails.
    uLongf small = 1000;
    CHECK(compress2(stream.data(), &small, source.data(), source.size(), 4) == Z_BUF_ERROR);
    for (int level : { -2, 10 }) {
        uLongf room = stream.size();
        CHECK(compress2(stream.data(), &room, source.data(), source.size(), level)
              == Z_STREAM_ERROR);
    }
}

TEST_CASE("defocus's zip outputs are deflated by libdeflate and read back exactly")
{
    const std::string dir = scratch_dir("zip_output");
    const std::string camera = " --focal 50 --fstop 1.8 --focus 4";
    const std::string zip = dir + "/zip.exr", none = dir + "/none.exr";
    std::string log;
    // LD_DEBUG=bindings logs where each symbol a library calls was found.
    REQUIRE(run("LD_DEBUG=bindings LD_DEBUG_OUTPUT=" + dir + "/bindings " + DEFOCUS_BIN + " "
                    + example_scene() + " -o " + zip + camera + " --compression zip",
                log)
            == 0);
    REQUIRE(run(std::string(DEFOCUS_BIN) + " " + example_scene() + " -o " + none + camera
                    + " --compression none",
                log)
            == 0);

    std::string bindings;
    std::vector<std::string> files;
    Filesystem::get_directory_entries(dir, files);
    for (const std::string& file : files) {
        std::string text;
        if (Strutil::contains(file, "bindings") && Filesystem::read_text_file(file, text))
            bindings += text;
    }
    const std::string program = Filesystem::filename(DEFOCUS_BIN);
    bool openexr_to_program = false, openexr_to_zlib = false;
    for (const std::string& line : Strutil::splitsv(bindings, "\n")) {
        if (!Strutil::contains(line, "libOpenEXR-") || !Strutil::ends_with(line, "`compress2'"))
            continue;
        openexr_to_program |= Strutil::contains(line, "/" + program + " [");
        openexr_to_zlib |= Strutil::contains(line, "libz.so");
    }
    CHECK(openexr_to_program);
    CHECK_FALSE(openexr_to_zlib);

    CHECK(Filesystem::file_size(zip) < Filesystem::file_size(none) / 2);
    const auto diff = ImageBufAlgo::compare(read_image(zip), read_image(none), 0.0f, 0.0f);
    CHECK(diff.nfail == 0);
    CHECK(diff.maxerror == 0.0);
}
