// See corners/simd.hpp: the 8-lane helpers are instantiated here, inlined only into AVX2 code.
#pragma GCC diagnostic ignored "-Wpsabi"

#include "simd.hpp"

namespace naneye::recon::simd {

bool has_avx2() {
  return __builtin_cpu_supports("avx2");
}

bool has_avx2_fma() {
  return has_avx2() && __builtin_cpu_supports("fma");
}

void shape_sse(const ModelParams& m, const float* yx, const float* yy, int n, float* U1, float* U2, float* E1,
               float* E2, float* G1, float* G2, float* S) {
  shape<V4>(m, yx, yy, n, U1, U2, E1, E2, G1, G2, S);
}

__attribute__((target("avx2,fma"))) void shape_avx2(const ModelParams& m, const float* yx, const float* yy,
                                                    int n, float* U1, float* U2, float* E1, float* E2,
                                                    float* G1, float* G2, float* S) {
  shape<V8>(m, yx, yy, n, U1, U2, E1, E2, G1, G2, S);
}

// Explicit specialisations, not instantiations of a template defined with the target attribute:
// GCC drops the attribute on the latter (the AVX2 versions came out as SSE code).
#define NANEYE_RESIDUALS(FREE)                                                                             \
  template <>                                                                                              \
  double residuals_jacobian_sse<FREE>(const ModelParams& m, const WindowArrays& in, int nv, float* r,      \
                                      const std::array<float*, 11>& J, const std::array<float*, 11>& Jw) { \
    return residuals_jacobian<V4, FREE>(m, in, nv, r, J, Jw);                                              \
  }                                                                                                        \
  template <>                                                                                              \
  __attribute__((target("avx2,fma"))) double residuals_jacobian_avx2<FREE>(                                \
      const ModelParams& m, const WindowArrays& in, int nv, float* r, const std::array<float*, 11>& J,     \
      const std::array<float*, 11>& Jw) {                                                                  \
    return residuals_jacobian<V8, FREE>(m, in, nv, r, J, Jw);                                              \
  }
NANEYE_RESIDUALS(false)
NANEYE_RESIDUALS(true)
#undef NANEYE_RESIDUALS

#define NANEYE_NORMAL(K)                                                                          \
  template <>                                                                                     \
  void normal_equations_sse<K>(const std::array<const float*, K + 1>& cols,                       \
                               const std::array<const float*, K>& jw, int nv,                     \
                               std::array<double, (K + 1) * K>& out) {                            \
    normal_equations<V4, K>(cols, jw, nv, out);                                                   \
  }                                                                                               \
  template <>                                                                                     \
  __attribute__((target("avx2,fma"))) void normal_equations_avx2<K>(                              \
      const std::array<const float*, K + 1>& cols, const std::array<const float*, K>& jw, int nv, \
      std::array<double, (K + 1) * K>& out) {                                                     \
    normal_equations<V8, K>(cols, jw, nv, out);                                                   \
  }
// The fits use 6 (linear start), 9 (fixed edges) and 11 (all) parameters.
NANEYE_NORMAL(6)
NANEYE_NORMAL(9)
NANEYE_NORMAL(11)
#undef NANEYE_NORMAL

}  // namespace naneye::recon::simd
