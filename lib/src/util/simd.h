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
/// the CPU runs picked at load time. clang (the sanitizer and fuzz builds)
/// takes the baseline alone: clang 14 compiles a function whose header
/// declares it without the attribute for the first target only, AVX-512,
/// and on a CPU without it the first such call traps (SIGILL).
#if defined(__clang__)
#define DEFOCUS_CLONES
#else
#define DEFOCUS_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#endif

namespace defocus {

using double4 = double __attribute__((vector_size(32)));
using float4 = float __attribute__((vector_size(16)));

/// A pixel's four channels. The vector is wrapped: clang refuses a bare
/// 32-byte vector as an argument or result in the baseline clone (an ABI
/// error, even for a function always inlined), and takes it in a struct.
struct d4 {
    double4 v;

    DEFOCUS_KERNEL double operator[](int i) const { return v[i]; }
    DEFOCUS_KERNEL d4& operator+=(const d4& b)
    {
        v += b.v;
        return *this;
    }
    DEFOCUS_KERNEL d4& operator-=(const d4& b)
    {
        v -= b.v;
        return *this;
    }
    DEFOCUS_KERNEL d4& operator*=(const d4& b)
    {
        v *= b.v;
        return *this;
    }
};

DEFOCUS_KERNEL d4 operator+(const d4& a, const d4& b)
{
    return { a.v + b.v };
}

DEFOCUS_KERNEL d4 operator-(const d4& a, const d4& b)
{
    return { a.v - b.v };
}

DEFOCUS_KERNEL d4 operator*(const d4& a, const d4& b)
{
    return { a.v * b.v };
}

DEFOCUS_KERNEL d4 load4(const double* p)
{
    d4 v;
    std::memcpy(&v.v, p, sizeof v.v);
    return v;
}

DEFOCUS_KERNEL void store4(double* p, const d4& v)
{
    std::memcpy(p, &v.v, sizeof v.v);
}

DEFOCUS_KERNEL d4 load4(const float* p)
{
    float4 v;
    std::memcpy(&v, p, sizeof v);
    return { __builtin_convertvector(v, double4) };
}

DEFOCUS_KERNEL void store4(float* p, const d4& v)
{
    const float4 f = __builtin_convertvector(v.v, float4);
    std::memcpy(p, &f, sizeof f);
}

DEFOCUS_KERNEL d4 splat(double w)
{
    return { double4 { w, w, w, w } };
}

}  // namespace defocus
