// The attribute that has the compiler build a function twice, for AVX2 (4 doubles a lane
// set) and for the x86-64 baseline, the loader picking one for the machine (internal
// header; GCC on x86-64, else nothing). Neither version enables fused multiply-add, so
// both round alike: the loops it marks give the same bits on any x86-64 machine.
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define SEMIOCTREE_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define SEMIOCTREE_VECTOR_CLONES
#endif
