#include "io/half_pixels.h"

#include <cpuid.h>
#include <immintrin.h>

#include <cstdint>

#include <OpenImageIO/parallel.h>

#include "util/fresh_image.h"
#include "util/parallel_rows.h"

namespace defocus {

namespace {

__attribute__((target("avx,f16c")))
void floats_to_halves(const float* in, uint16_t* out, size_t n)
{
    size_t i = 0;
    for (; i + 8 <= n; i += 8)
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i),
                         _mm256_cvtps_ph(_mm256_loadu_ps(in + i), _MM_FROUND_TO_NEAREST_INT));
    for (; i < n; ++i)
        out[i] = uint16_t(_mm_extract_epi16(_mm_cvtps_ph(_mm_set_ss(in[i]),
                                                          _MM_FROUND_TO_NEAREST_INT), 0));
}

/// F16C conversions and the AVX registers they use, enabled by the OS.
/// (clang 14's __builtin_cpu_supports does not know "f16c": cpuid says.)
bool has_f16c()
{
    unsigned a = 0, b = 0, c = 0, d = 0;
    return __builtin_cpu_supports("avx") && __get_cpuid(1, &a, &b, &c, &d) && (c & bit_F16C);
}

}  // namespace

bool convert_to_half(const OIIO::ImageBuf& src, OIIO::ImageBuf& dst, int nthreads)
{
    const OIIO::ImageSpec& from = src.spec();
    if (from.format != OIIO::TypeFloat || !from.channelformats.empty() || !src.localpixels()
        || !has_f16c())
        return false;
    OIIO::ImageSpec spec = from;
    spec.set_format(OIIO::TypeHalf);
    reset_for_overwrite(dst, spec, nthreads);
    const size_t row_values = size_t(from.width) * from.nchannels;
    OIIO::parallel_for(int64_t(0), int64_t(from.height) * from.depth, [&](int64_t row) {
        const float* in = static_cast<const float*>(src.localpixels()) + size_t(row) * row_values;
        uint16_t* out = static_cast<uint16_t*>(dst.localpixels()) + size_t(row) * row_values;
        floats_to_halves(in, out, row_values);
    }, by_rows(nthreads));
    return true;
}

}  // namespace defocus
