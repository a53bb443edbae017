#include "io/exr_zip.h"

#include <cstdint>
#include <memory>
#include <new>
#include <vector>

#include <libdeflate.h>

namespace defocus {

namespace {

struct FreeDecompressor {
    void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
};

/// Undoes what OpenEXR's ZIP compressor does before deflating, in
/// `bytes` and into `out`: each byte was stored as its difference to the
/// one before plus 128, and the even bytes of the chunk before the odd.
void undo_predictor_and_split(uint8_t* bytes, uint8_t* out, size_t n)
{
    for (size_t i = 1; i < n; ++i)
        bytes[i] = uint8_t(bytes[i - 1] + bytes[i] - 128);
    const size_t half = (n + 1) / 2;
    for (size_t i = 0; i < n / 2; ++i) {
        out[2 * i] = bytes[i];
        out[2 * i + 1] = bytes[half + i];
    }
    if (n % 2)
        out[n - 1] = bytes[half - 1];
}

exr_result_t inflate_zip_chunk(exr_decode_pipeline_t* decode)
{
    const auto& zip = *static_cast<const ZipChunks*>(decode->decoding_user_data);
    const uint64_t packed = decode->chunk.packed_size, unpacked = decode->chunk.unpacked_size;
    // A chunk that deflating did not shrink is stored as it is; and only
    // a pipeline that has its output buffer ready is served here.
    if (packed == unpacked || unpacked == 0 || !decode->unpacked_buffer
        || decode->unpacked_buffer == decode->packed_buffer
        || decode->unpacked_alloc_size < unpacked)
        return zip.fallback(decode);
    thread_local std::unique_ptr<libdeflate_decompressor, FreeDecompressor> inflater(
        libdeflate_alloc_decompressor());
    thread_local std::vector<uint8_t> inflated;
    if (!inflater)
        return EXR_ERR_OUT_OF_MEMORY;
    try {  // nothing may be thrown through OpenEXR's C code
        inflated.resize(unpacked);
    } catch (const std::bad_alloc&) {
        return EXR_ERR_OUT_OF_MEMORY;
    }
    size_t size = 0;
    if (libdeflate_zlib_decompress(inflater.get(), decode->packed_buffer, packed, inflated.data(),
                                   unpacked, &size)
            != LIBDEFLATE_SUCCESS
        || size != unpacked)
        return EXR_ERR_CORRUPT_CHUNK;
    undo_predictor_and_split(inflated.data(), static_cast<uint8_t*>(decode->unpacked_buffer),
                             unpacked);
    if (inflated.capacity() > (size_t(64) << 20))  // a huge tile: not kept for the next file
        std::vector<uint8_t>().swap(inflated);
    return EXR_ERR_SUCCESS;
}

}  // namespace

void inflate_zip_chunks(exr_decode_pipeline_t& decoder, exr_compression_t compression,
                        ZipChunks& zip)
{
    if (!decoder.decompress_fn
        || (compression != EXR_COMPRESSION_ZIP && compression != EXR_COMPRESSION_ZIPS))
        return;
    zip.fallback = decoder.decompress_fn;
    decoder.decoding_user_data = &zip;
    decoder.decompress_fn = &inflate_zip_chunk;
}

}  // namespace defocus
