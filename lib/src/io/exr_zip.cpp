#include "io/exr_zip.h"

#include <emmintrin.h>

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

/// bytes[i] = bytes[i - 1] + bytes[i] - 128 for i >= 1, in order (mod 256):
/// OpenEXR's ZIP predictor stores each byte as its difference to the one
/// before, plus 128. Summed one byte after another, the 4K example's 246
/// MB of pixels made this function 7% of the frame's CPU time (2% now):
/// here each 16 bytes are summed within a vector in four shifted adds, and
/// only the last byte of the 16 is carried on to the next (SSE2, which
/// every x86-64 processor has).
void undo_predictor(uint8_t* bytes, size_t n)
{
    if (n < 2)
        return;
    size_t i = 1;
    const __m128i bias = _mm_set1_epi8(char(0x80));  // - 128 = + 128 (mod 256)
    __m128i carry = _mm_set1_epi8(char(bytes[0]));
    for (; i + 16 <= n; i += 16) {
        __m128i x = _mm_xor_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(bytes + i)),
                                  bias);
        x = _mm_add_epi8(x, _mm_slli_si128(x, 1));
        x = _mm_add_epi8(x, _mm_slli_si128(x, 2));
        x = _mm_add_epi8(x, _mm_slli_si128(x, 4));
        x = _mm_add_epi8(x, _mm_slli_si128(x, 8));
        x = _mm_add_epi8(x, carry);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(bytes + i), x);
        // The last byte, in every lane.
        const __m128i high = _mm_unpackhi_epi8(x, x);
        carry = _mm_shuffle_epi32(_mm_shufflehi_epi16(high, 0xff), 0xff);
    }
    for (; i < n; ++i)
        bytes[i] = uint8_t(bytes[i - 1] + bytes[i] - 128);
}

/// Undoes what OpenEXR's ZIP compressor does before deflating, in
/// `bytes` and into `out`: the predictor, then the even bytes of the chunk
/// stored before the odd.
void undo_predictor_and_split(uint8_t* bytes, uint8_t* out, size_t n)
{
    undo_predictor(bytes, n);
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
