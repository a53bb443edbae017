// Internal: kernels compiled for several instruction sets, the one the
// CPU runs picked at load time.
#pragma once

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
