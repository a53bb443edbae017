// Internal: kernels compiled for several instruction sets, the one the
// CPU runs picked at load time, and the 4-double vectors they work in.
#pragma once

// The vector helpers below are inlined into each clone of the kernels, so
// the ABI of passing them by value never applies.
#pragma GCC diagnostic ignored "-Wpsabi"

#include <cstring>

/// The kernels are inlined into each target_clones clone of their callers,
/// so that they are compiled for that clone's instruction set.
#define DEFOCUS_KERNEL inline __attribute__((always_inline))
/// The callers are compiled for AVX-512, AVX2 and the baseline, the one
/// the CPU runs picked at load time. clang 14 refuses 4-double vectors in
/// the baseline clone of such a function (an ABI error, not a warning),
/// so a clang build has the baseline only: slower, the same results.
#if defined(__clang__)
#define DEFOCUS_CLONES
#else
#define DEFOCUS_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#endif

namespace defocus {

/// A pixel's four channels.
using d4 = double __attribute__((vector_size(32)));
using f4 = float __attribute__((vector_size(16)));

DEFOCUS_KERNEL d4 load4(const double* p)
{
    d4 v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

DEFOCUS_KERNEL void store4(double* p, const d4& v)
{
    std::memcpy(p, &v, sizeof v);
}

DEFOCUS_KERNEL d4 load4(const float* p)
{
    f4 v;
    std::memcpy(&v, p, sizeof v);
    return __builtin_convertvector(v, d4);
}

DEFOCUS_KERNEL void store4(float* p, const d4& v)
{
    const f4 f = __builtin_convertvector(v, f4);
    std::memcpy(p, &f, sizeof f);
}

DEFOCUS_KERNEL d4 splat(double w)
{
    return d4 { w, w, w, w };
}

}  // namespace defocus
