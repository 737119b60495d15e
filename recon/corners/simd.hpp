#pragma once
// The two innermost loops of the corner fit (corners/fast_fit.cpp) written once over a GCC vector
// type and compiled twice: 4 floats (SSE2, the x86-64 baseline every build runs) and 8 floats in
// functions compiled for AVX2 + FMA, chosen at run time (has_avx2_fma). No Eigen inside:
// Eigen fixes its packet size per translation unit, and two sizes of the same Eigen template in
// one program would violate the one-definition rule; these plain loops are always inlined into
// their entry points, so each entry point holds its own code.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>

namespace naneye::recon::simd {

// The 8-lane code only ever runs inlined into AVX2 functions, never across a call boundary whose
// ABI would depend on the target: GCC's note about that ABI does not apply.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

using V4 = float __attribute__((vector_size(16)));
using V8 = float __attribute__((vector_size(32)));
using VI4 = std::int32_t __attribute__((vector_size(16)));
using VI8 = std::int32_t __attribute__((vector_size(32)));
template <class V>
struct IntVector;
template <>
struct IntVector<V4> {
  using type = VI4;
};
template <>
struct IntVector<V8> {
  using type = VI8;
};
template <class V>
using VInt = typename IntVector<V>::type;

template <class V>
constexpr int kLanes = static_cast<int>(sizeof(V) / sizeof(float));

#define NANEYE_SIMD_INLINE inline __attribute__((always_inline))

template <class V>
NANEYE_SIMD_INLINE V load(const float* p) {
  V v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
template <class V>
NANEYE_SIMD_INLINE void store(float* p, V v) {
  std::memcpy(p, &v, sizeof v);
}
template <class V>
NANEYE_SIMD_INLINE V splat(float x) {
  return x - V{};  // broadcast (GCC vector semantics: scalar op vector)
}

// exp(x) for x <= 0: Cody-Waite range reduction x = n ln2 + r, |r| <= ln2 / 2, and the degree-6
// polynomial of Cephes' expf (S. L. Moshier, Cephes Math Library, expf.c), ~1 ulp; 2^n built in
// the exponent bits. Arguments below -87.3 are held there (exp = 1.2e-38, the smallest normal
// float): no denormals, and no overflow of the exponent field.
template <class V>
NANEYE_SIMD_INLINE V exp_nonpositive(V x) {
  using VI = VInt<V>;
  x = x < splat<V>(-87.3f) ? splat<V>(-87.3f) : x;
  const V t = x * 1.44269504088896341f + 0.5f;  // n = floor(t) = round(x / ln2)
  VI n = __builtin_convertvector(t, VI);        // truncates toward zero: one too high where t < 0
  V fn = __builtin_convertvector(n, V);
  n += static_cast<VI>(fn > t);  // comparisons give -1 (true) or 0 per lane
  fn = __builtin_convertvector(n, V);
  x = x - fn * 0.693359375f - fn * -2.12194440e-4f;
  const V z = x * x;
  V y = splat<V>(1.9875691500e-4f);
  y = y * x + 1.3981999507e-3f;
  y = y * x + 8.3334519073e-3f;
  y = y * x + 4.1665795894e-2f;
  y = y * x + 1.6666665459e-1f;
  y = y * x + 5.0000001201e-1f;
  y = y * z + x + 1.0f;
  const VI bits = (n + 127) << 23;
  V scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return y * scale;
}

// erf(z) and exp(-z^2) together: Abramowitz & Stegun 7.1.26 (|error| <= 1.5e-7), which needs
// exp(-z^2) anyway, as the derivative of erf does.
template <class V>
NANEYE_SIMD_INLINE void erf_gauss(V z, V& e, V& g) {
  g = exp_nonpositive<V>(-(z * z));
  const V az = z < 0.0f ? -z : z;
  const V t = 1.0f / (1.0f + 0.3275911f * az);
  V poly = splat<V>(1.061405429f);
  poly = poly * t - 1.453152027f;
  poly = poly * t + 1.421413741f;
  poly = poly * t - 0.284496736f;
  poly = poly * t + 0.254829592f;
  const V y = 1.0f - poly * t * g;
  e = z < 0.0f ? -y : y;
}

// The model at the window's pixels (corners/fast_fit.hpp), its parameters in float.
struct ModelParams {
  float qx, qy, c1, s1, c2, s2, k, inv_s, a, gx, gy, b, hx, hy;
};

// Edges within this of perpendicular (|rho| = |n1 . n2|, the cosine of the angle between the
// normals) use the product of erfs, which is the blurred corner exactly at rho = 0; its misfit grows
// with |rho| (docs/experiments/wedge_fit.cpp: 1.5-2 % of |b| at 80 degrees, 4.4-5.7 % at 60), and
// beyond 0.1 (6 degrees off, ~1 % of |b|: a third of the simulator's 99.9th-percentile misfit) the
// exact form costs 8 more exponentials and 2 erfs per pixel rather than a biased corner.
inline constexpr float kExactCornerRho = 0.1f;

// Gauss-Legendre, 8 nodes on [-1, 1] (abscissae and weights, the positive half).
inline constexpr std::array<float, 4> kGaussLegendreX = {0.18343464249564980f, 0.52553240991632899f,
                                                         0.79666647741362674f, 0.96028985649753623f};
inline constexpr std::array<float, 4> kGaussLegendreW = {0.36268378337836198f, 0.31370664587788729f,
                                                         0.22238103445337447f, 0.10122853629037626f};

// u1, u2 and the model's shape S for the window's n pixels (rounded up to whole vectors: the arrays
// hold kMaxPixels, a multiple of 8), with what its derivatives need: dS/du1 = (2 / sqrt pi) k G1 E2
// and dS/du2 = (2 / sqrt pi) k G2 E1. For perpendicular edges S = E1 E2, E_k = erf(k u_k), G_k =
// exp(-(k u_k)^2). Otherwise the blurred X-junction is E[sign X1 sign X2] for X_k ~ N(sqrt2 k u_k, 1)
// correlated by rho (Drezner & Wesolowsky 1990, with z_k = k u_k):
//   S = erf(z1) erf(z2) + (2 / pi) int_0^rho exp(-(z1^2 - 2 r z1 z2 + z2^2) / (1 - r^2)) dr / sqrt(1 - r^2),
// and E2, E1 above become erf((z2 - rho z1) / sqrt(1 - rho^2)) and erf((z1 - rho z2) / sqrt(1 - rho^2)).
// (The integral's derivative in rho is left out of the free-edge fit's Jacobian: that fit only seeds
// the one with the grid's edges, whose rho is fixed.)
template <class V>
NANEYE_SIMD_INLINE void shape(const ModelParams& m, const float* yx, const float* yy, int n, float* U1,
                              float* U2, float* E1, float* E2, float* G1, float* G2, float* S) {
  constexpr int L = kLanes<V>;
  // Parallel edges make no corner; the free-edge fit can still wander there, and 1 - rho^2 <= 0
  // (rounding can put |rho| past 1) would turn the model into inf / NaN. 0.999: 2.6 degrees.
  const float rho = std::clamp(m.c1 * m.c2 + m.s1 * m.s2, -0.999f, 0.999f);
  const bool exact = rho > kExactCornerRho || rho < -kExactCornerRho;
  std::array<float, 8> node_r{}, node_c{}, node_w{};
  float cross = 0;
  if (exact) {
    for (std::size_t j = 0; j < 8; ++j) {
      const float x = j < 4 ? -kGaussLegendreX[3 - j] : kGaussLegendreX[j - 4];
      const float w = j < 4 ? kGaussLegendreW[3 - j] : kGaussLegendreW[j - 4];
      const float r = 0.5f * rho * (1.0f + x);
      node_r[j] = r;
      node_c[j] = 1.0f / (1.0f - r * r);
      node_w[j] = 0.63661977236758134f * 0.5f * rho * w * __builtin_sqrtf(node_c[j]);  // 2 / pi
    }
    cross = 1.0f / __builtin_sqrtf(1.0f - rho * rho);
  }
  for (int i = 0; i < n; i += L) {
    const V x = load<V>(yx + i) - m.qx, y = load<V>(yy + i) - m.qy;
    const V u1 = m.c1 * x + m.s1 * y, u2 = m.c2 * x + m.s2 * y;
    const V z1 = m.k * u1, z2 = m.k * u2;
    V e1, g1, e2, g2;
    erf_gauss<V>(z1, e1, g1);
    erf_gauss<V>(z2, e2, g2);
    V s = e1 * e2;
    if (exact) {
      const V zz = z1 * z1 + z2 * z2, z12 = z1 * z2;
#pragma GCC unroll 8
      for (std::size_t j = 0; j < 8; ++j) {
        s += node_w[j] * exp_nonpositive<V>(-((zz - (2.0f * node_r[j]) * z12) * node_c[j]));
      }
      V unused;
      erf_gauss<V>((z2 - rho * z1) * cross, e2, unused);
      erf_gauss<V>((z1 - rho * z2) * cross, e1, unused);
    }
    store(U1 + i, u1);
    store(U2 + i, u2);
    store(E1 + i, e1);
    store(E2 + i, e2);
    store(G1 + i, g1);
    store(G2 + i, g2);
    store(S + i, s);
  }
}

// The window (inputs) and the geometry shape() computed at the same parameters.
struct WindowArrays {
  const float *yx, *yy, *dx, *dy, *val, *wt, *U1, *U2, *E1, *E2, *G1, *G2, *S;
};

// Residuals r, the weighted cost sum wt r^2, the Jacobian columns of the active parameters and their
// weighted copies, in one pass. Columns: qx qy [theta1 theta2] s a gx gy b hx hy (the edge normals
// only with FreeEdges). The arrays' tails up to nv hold zero weight.
template <class V, bool FreeEdges>
NANEYE_SIMD_INLINE double residuals_jacobian(const ModelParams& m, const WindowArrays& in, int nv, float* r,
                                             const std::array<float*, 11>& J,
                                             const std::array<float*, 11>& Jw) {
  constexpr int L = kLanes<V>;
  constexpr int K = FreeEdges ? 11 : 9;
  const float kk = 1.12837916709551257390f * m.k;  // d erf(k u) / du = (2 / sqrt(pi)) k exp(-(k u)^2)
  V cost = {};
  for (int i = 0; i < nv; i += L) {
    const V dx = load<V>(in.dx + i), dy = load<V>(in.dy + i), S = load<V>(in.S + i), wt = load<V>(in.wt + i);
    const V C = m.b + m.hx * dx + m.hy * dy;
    const V res = m.a + m.gx * dx + m.gy * dy + C * S - load<V>(in.val + i);
    store(r + i, res);
    cost += wt * res * res;
    // A = C dS/du1, B = C dS/du2.
    const V A = load<V>(in.G1 + i) * (kk * C * load<V>(in.E2 + i));
    const V B = load<V>(in.G2 + i) * (kk * C * load<V>(in.E1 + i));
    V col[K];
    int j = 0;
    col[j++] = -(A * m.c1 + B * m.c2);
    col[j++] = -(A * m.s1 + B * m.s2);
    if constexpr (FreeEdges) {
      const V x = load<V>(in.yx + i) - m.qx, y = load<V>(in.yy + i) - m.qy;
      col[j++] = A * (-m.s1 * x + m.c1 * y);
      col[j++] = B * (-m.s2 * x + m.c2 * y);
    }
    col[j++] = -(A * load<V>(in.U1 + i) + B * load<V>(in.U2 + i)) * m.inv_s;
    col[j++] = splat<V>(1.0f);
    col[j++] = dx;
    col[j++] = dy;
    col[j++] = S;
    col[j++] = dx * S;
    col[j++] = dy * S;
#pragma GCC unroll 11
    for (int c = 0; c < K; ++c) {
      store(J[static_cast<std::size_t>(c)] + i, col[c]);
      store(Jw[static_cast<std::size_t>(c)] + i, wt * col[c]);
    }
  }
  float total = 0;
  for (int l = 0; l < L; ++l) total += cost[l];
  return static_cast<double>(total);
}

// One row A of the normal equations: sum_i jw[i] * cols[b][i] for b = A..K (cols[K] is the
// right-hand side), all in registers in one pass. n4 is a multiple of the vector length and the
// columns are zero from n to n4.
template <class V, int K, int A>
NANEYE_SIMD_INLINE void normal_row(const std::array<const float*, K + 1>& cols, const float* jw, int nv,
                                   std::array<double, (K + 1) * K>& out) {
  constexpr int m = K + 1 - A;
  constexpr int L = kLanes<V>;
  V acc[m] = {};
  for (int i = 0; i < nv; i += L) {
    const V x = load<V>(jw + i);
#pragma GCC unroll 12
    for (int b = 0; b < m; ++b) acc[b] += x * load<V>(cols[static_cast<std::size_t>(A + b)] + i);
  }
  for (int b = 0; b < m; ++b) {
    float s = 0;
    for (int l = 0; l < L; ++l) s += acc[b][l];
    out[static_cast<std::size_t>(A * (K + 1) + A + b)] = static_cast<double>(s);
  }
}

// Rows A..K-1 of [Jw' J | Jw' y] into out (row-major, K + 1 per row; the lower triangle unset).
template <class V, int K, int A = 0>
NANEYE_SIMD_INLINE void normal_equations(const std::array<const float*, K + 1>& cols,
                                         const std::array<const float*, K>& jw, int nv,
                                         std::array<double, (K + 1) * K>& out) {
  normal_row<V, K, A>(cols, jw[static_cast<std::size_t>(A)], nv, out);
  if constexpr (A + 1 < K) normal_equations<V, K, A + 1>(cols, jw, nv, out);
}

// The CPU's vector extensions, one test each of the word libgcc fills at start-up, for every kernel
// that picks its width at run time: AVX2 (the scene kernels, which never fuse a multiply-add, so
// that every width gives the same bits) and AVX2 + FMA (the corner fits below).
bool has_avx2();
bool has_avx2_fma();

// Entry points (corners/simd.cpp): the same loops for 4 and 8 lanes.
void shape_sse(const ModelParams& m, const float* yx, const float* yy, int n, float* U1, float* U2, float* E1,
               float* E2, float* G1, float* G2, float* S);
void shape_avx2(const ModelParams& m, const float* yx, const float* yy, int n, float* U1, float* U2,
                float* E1, float* E2, float* G1, float* G2, float* S);
template <bool FreeEdges>
double residuals_jacobian_sse(const ModelParams& m, const WindowArrays& in, int nv, float* r,
                              const std::array<float*, 11>& J, const std::array<float*, 11>& Jw);
template <bool FreeEdges>
double residuals_jacobian_avx2(const ModelParams& m, const WindowArrays& in, int nv, float* r,
                               const std::array<float*, 11>& J, const std::array<float*, 11>& Jw);
template <int K>
void normal_equations_sse(const std::array<const float*, K + 1>& cols, const std::array<const float*, K>& jw,
                          int nv, std::array<double, (K + 1) * K>& out);
template <int K>
void normal_equations_avx2(const std::array<const float*, K + 1>& cols, const std::array<const float*, K>& jw,
                           int nv, std::array<double, (K + 1) * K>& out);

#pragma GCC diagnostic pop

}  // namespace naneye::recon::simd
