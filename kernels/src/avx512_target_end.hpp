// Private, no include guard: closes the region avx512_target_begin.hpp opened.
#ifndef NBV_EMULATE_AVX512
#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC diagnostic pop
#pragma GCC pop_options
#endif
#endif  // NBV_EMULATE_AVX512
