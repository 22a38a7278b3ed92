// Private, no include guard: opens the region in which an -mavx2 source compiles its own
// functions for AVX-512 F/VL/DQ/BW; avx512_target_end.hpp closes it. Include every header the
// region's code shares with other sources (ray_keys.hpp, Eigen, ...) before it, so that their
// inline functions are compiled here as in the AVX2 and scalar sources, and whichever copy the
// linker keeps runs on a CPU without AVX-512. With NBV_EMULATE_AVX512 there is no region: the
// lanes are plain C++ (simd_emulated.hpp).
#ifndef NBV_EMULATE_AVX512
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx512f,avx512vl,avx512dq,avx512bw"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx512f,avx512vl,avx512dq,avx512bw")
// GCC 12's AVX-512 intrinsics start from _mm512_undefined_*(), which -Wmaybe-uninitialized
// and -Wuninitialized take for an uninitialised read (GCC bug 105593).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
#endif
#endif  // NBV_EMULATE_AVX512
