# NBV_PLAIN_LANES_FLAGS: the options of the sources that hold the plain C++ SIMD lanes
# (kernels/src/simd_emulated.hpp). With GCC, -Wno-psabi: their 64-byte structs pass by value
# between functions of one library, and GCC notes on each that this ABI changed in GCC 4.6.
# And SLP vectorization off where this compiler drops a single-precision rounding in
# SLP-vectorized code. GCC 12.2 (Debian 12) compiles
#   struct P { float x, y; };  P p{(float)a[0], (float)a[1]};  out[0] = p.x;  out[1] = p.y;
# at -O2 as out[i] = a[i]. The plain C++ SIMD lanes (kernels/src/simd_emulated.hpp) are such
# code; nbv's results with and without the option are compared in docs/performance-log.md
# ("The AVX-512 walks on a CPU without AVX-512").
set(NBV_PLAIN_LANES_FLAGS "")
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  list(APPEND NBV_PLAIN_LANES_FLAGS -Wno-psabi)
endif()
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND NOT CMAKE_CROSSCOMPILING)
  set(check_source "${CMAKE_BINARY_DIR}/nbv_checks/float_rounding_kept.cpp")
  file(WRITE "${check_source}" [=[
struct P {
  float x, y;
};
__attribute__((noinline)) void roundTwice(double* out, const double* a) {
  const P p{static_cast<float>(a[0]), static_cast<float>(a[1])};
  out[0] = p.x;
  out[1] = p.y;
}
int main() {
  const double a[2] = {0.1, 0.2};
  double out[2];
  roundTwice(out, a);
  return out[0] == static_cast<double>(0.1f) && out[1] == static_cast<double>(0.2f) ? 0 : 1;
}
]=])
  try_run(nbv_rounding_run nbv_rounding_compiled "${CMAKE_BINARY_DIR}/nbv_checks" "${check_source}"
          COMPILE_DEFINITIONS -O2)
  if(nbv_rounding_compiled AND NOT nbv_rounding_run EQUAL 0)
    list(APPEND NBV_PLAIN_LANES_FLAGS -fno-tree-slp-vectorize)
    message(STATUS "nbv: ${CMAKE_CXX_COMPILER_ID} ${CMAKE_CXX_COMPILER_VERSION} drops a float rounding when it "
                   "SLP-vectorizes; the plain C++ SIMD lanes are built with -fno-tree-slp-vectorize")
  endif()
endif()
