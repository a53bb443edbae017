// zlib's one-call compression, compress() and compress2(), answered by
// libdeflate for the whole of a tool's process.
//
// OpenEXR 3.1 deflates every ZIP and ZIPS chunk it writes with compress2(),
// and its C++ writer, which OpenImageIO uses, has no hook to replace it.
// The tools export these definitions (utils/CMakeLists.txt), so the
// dynamic loader binds OpenEXR's calls to them rather than to libz: the
// program comes first in the lookup scope. libdeflate writes the same zlib
// format two-thirds faster at the same level (a 4K frame's 86 MB of half
// pixels, one thread, level 4: 0.28 s against 0.47 s), at sizes within a
// few percent; any zlib reader inflates its streams.
//
// Only the executables take this: a process that loads the library
// (oiiotool, Python) keeps its own zlib.
#include <zlib.h>

#include <dlfcn.h>

#include <array>
#include <memory>

#include <libdeflate.h>

namespace {

struct FreeCompressor {
    void operator()(libdeflate_compressor* c) const { libdeflate_free_compressor(c); }
};

using Compress2 = int (*)(Bytef*, uLongf*, const Bytef*, uLong, int);

/// zlib's own compress2, for what libdeflate does not take: level 0, and
/// a destination too small for libdeflate's stream (zlib may still fit
/// its own, or it reports the same Z_BUF_ERROR a caller expects).
int zlib_compress2(Bytef* dest, uLongf* dest_len, const Bytef* source, uLong source_len,
                   int level)
{
    static const auto zlib = reinterpret_cast<Compress2>(dlsym(RTLD_NEXT, "compress2"));
    return zlib ? zlib(dest, dest_len, source, source_len, level) : Z_STREAM_ERROR;
}

}  // namespace

extern "C" int compress2(Bytef* dest, uLongf* dest_len, const Bytef* source, uLong source_len,
                         int level)
{
    if (level == Z_DEFAULT_COMPRESSION)
        level = 6;  // zlib's default
    if (level < 0 || level > 9)
        return Z_STREAM_ERROR;
    if (level == 0)
        return zlib_compress2(dest, dest_len, source, source_len, level);
    // One compressor per level and thread: each holds its hash tables.
    thread_local std::array<std::unique_ptr<libdeflate_compressor, FreeCompressor>, 10> by_level;
    auto& compressor = by_level[size_t(level)];
    if (!compressor)
        compressor.reset(libdeflate_alloc_compressor(level));
    if (!compressor)
        return Z_MEM_ERROR;
    const size_t size = libdeflate_zlib_compress(compressor.get(), source, source_len, dest,
                                                 *dest_len);
    if (size == 0)
        return zlib_compress2(dest, dest_len, source, source_len, level);
    *dest_len = uLongf(size);
    return Z_OK;
}

extern "C" int compress(Bytef* dest, uLongf* dest_len, const Bytef* source, uLong source_len)
{
    return compress2(dest, dest_len, source, source_len, Z_DEFAULT_COMPRESSION);
}
