// Small vector and 3x3 matrix types of the SPH GPU path (thesis 8.1, 8.2), usable from CUDA device code and
// plain C++ alike (RC_HD is __host__ __device__ under nvcc and empty for g++). Templated on the scalar: the
// GPU runs float, the host driver float or double.
#pragma once

#include <math.h>

#include <cstdint>

#ifdef __CUDACC__
#define RC_HD __host__ __device__ __forceinline__
#else
#define RC_HD inline
#endif

namespace rc {

RC_HD float sphSqrt(float x) {
  return sqrtf(x);
}
RC_HD double sphSqrt(double x) {
  return sqrt(x);
}
RC_HD float sphCbrt(float x) {
  return cbrtf(x);
}
RC_HD double sphCbrt(double x) {
  return cbrt(x);
}
RC_HD float sphPow(float x, float y) {
  return powf(x, y);
}
RC_HD double sphPow(double x, double y) {
  return pow(x, y);
}
RC_HD float sphAbs(float x) {
  return fabsf(x);
}
RC_HD double sphAbs(double x) {
  return fabs(x);
}
template <class R>
RC_HD R sphMin(R a, R b) {
  return a < b ? a : b;
}
template <class R>
RC_HD R sphMax(R a, R b) {
  return a > b ? a : b;
}

template <class R>
struct SphGpuVec3 {
  R x, y, z;
};

/// Storage type: four scalars, aligned so that float loads are single 16-byte transactions.
template <class R>
struct alignas(4 * sizeof(R)) SphGpuVec4 {
  R x, y, z, w;
};

template <class R>
RC_HD SphGpuVec3<R> vec3(R x, R y, R z) {
  return {x, y, z};
}
template <class R>
RC_HD SphGpuVec3<R> xyz(const SphGpuVec4<R>& v) {
  return {v.x, v.y, v.z};
}
template <class R>
RC_HD SphGpuVec4<R> vec4(const SphGpuVec3<R>& v, R w) {
  return {v.x, v.y, v.z, w};
}
template <class R>
RC_HD SphGpuVec3<R> operator+(const SphGpuVec3<R>& a, const SphGpuVec3<R>& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
template <class R>
RC_HD SphGpuVec3<R> operator-(const SphGpuVec3<R>& a, const SphGpuVec3<R>& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
template <class R>
RC_HD SphGpuVec3<R> operator-(const SphGpuVec3<R>& a) {
  return {-a.x, -a.y, -a.z};
}
template <class R>
RC_HD SphGpuVec3<R> operator*(R s, const SphGpuVec3<R>& a) {
  return {s * a.x, s * a.y, s * a.z};
}
template <class R>
RC_HD SphGpuVec3<R>& operator+=(SphGpuVec3<R>& a, const SphGpuVec3<R>& b) {
  a.x += b.x, a.y += b.y, a.z += b.z;
  return a;
}
template <class R>
RC_HD SphGpuVec3<R>& operator-=(SphGpuVec3<R>& a, const SphGpuVec3<R>& b) {
  a.x -= b.x, a.y -= b.y, a.z -= b.z;
  return a;
}
template <class R>
RC_HD R dot(const SphGpuVec3<R>& a, const SphGpuVec3<R>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class R>
RC_HD SphGpuVec3<R> cross(const SphGpuVec3<R>& a, const SphGpuVec3<R>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

/// Row-major 3x3 matrix.
template <class R>
struct SphGpuMat3 {
  R m[3][3];
};

template <class R>
RC_HD SphGpuMat3<R> zeroMat3() {
  SphGpuMat3<R> a;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) a.m[i][j] = R(0);
  return a;
}
template <class R>
RC_HD SphGpuMat3<R> identityMat3() {
  SphGpuMat3<R> a = zeroMat3<R>();
  a.m[0][0] = a.m[1][1] = a.m[2][2] = R(1);
  return a;
}
template <class R>
RC_HD SphGpuVec3<R> operator*(const SphGpuMat3<R>& a, const SphGpuVec3<R>& v) {
  return {a.m[0][0] * v.x + a.m[0][1] * v.y + a.m[0][2] * v.z,
          a.m[1][0] * v.x + a.m[1][1] * v.y + a.m[1][2] * v.z,
          a.m[2][0] * v.x + a.m[2][1] * v.y + a.m[2][2] * v.z};
}
template <class R>
RC_HD SphGpuMat3<R> operator*(const SphGpuMat3<R>& a, const SphGpuMat3<R>& b) {
  SphGpuMat3<R> c;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      c.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
  return c;
}
template <class R>
RC_HD SphGpuMat3<R> transposed(const SphGpuMat3<R>& a) {
  SphGpuMat3<R> t;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) t.m[i][j] = a.m[j][i];
  return t;
}
template <class R>
RC_HD R determinant(const SphGpuMat3<R>& a) {
  return a.m[0][0] * (a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1]) -
         a.m[0][1] * (a.m[1][0] * a.m[2][2] - a.m[1][2] * a.m[2][0]) +
         a.m[0][2] * (a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0]);
}
/// Inverse by the adjugate (the caller checks the determinant).
template <class R>
RC_HD SphGpuMat3<R> inverted(const SphGpuMat3<R>& a) {
  const R inv_det = R(1) / determinant(a);
  SphGpuMat3<R> b;
  b.m[0][0] = (a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1]) * inv_det;
  b.m[0][1] = (a.m[0][2] * a.m[2][1] - a.m[0][1] * a.m[2][2]) * inv_det;
  b.m[0][2] = (a.m[0][1] * a.m[1][2] - a.m[0][2] * a.m[1][1]) * inv_det;
  b.m[1][0] = (a.m[1][2] * a.m[2][0] - a.m[1][0] * a.m[2][2]) * inv_det;
  b.m[1][1] = (a.m[0][0] * a.m[2][2] - a.m[0][2] * a.m[2][0]) * inv_det;
  b.m[1][2] = (a.m[0][2] * a.m[1][0] - a.m[0][0] * a.m[1][2]) * inv_det;
  b.m[2][0] = (a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0]) * inv_det;
  b.m[2][1] = (a.m[0][1] * a.m[2][0] - a.m[0][0] * a.m[2][1]) * inv_det;
  b.m[2][2] = (a.m[0][0] * a.m[1][1] - a.m[0][1] * a.m[1][0]) * inv_det;
  return b;
}
/// a += w u v^T.
template <class R>
RC_HD void addOuter(SphGpuMat3<R>& a, R w, const SphGpuVec3<R>& u, const SphGpuVec3<R>& v) {
  const R wu[3] = {w * u.x, w * u.y, w * u.z};
  for (int i = 0; i < 3; ++i) {
    a.m[i][0] += wu[i] * v.x;
    a.m[i][1] += wu[i] * v.y;
    a.m[i][2] += wu[i] * v.z;
  }
}
/// a += w (|p|^2 I - p p^T), the inertia of a point of weight w at p.
template <class R>
RC_HD void addInertia(SphGpuMat3<R>& a, R w, const SphGpuVec3<R>& p) {
  const R xx = p.x * p.x, yy = p.y * p.y, zz = p.z * p.z;
  a.m[0][0] += w * (yy + zz), a.m[1][1] += w * (xx + zz), a.m[2][2] += w * (xx + yy);
  const R xy = -w * p.x * p.y, xz = -w * p.x * p.z, yz = -w * p.y * p.z;
  a.m[0][1] += xy, a.m[1][0] += xy, a.m[0][2] += xz, a.m[2][0] += xz, a.m[1][2] += yz, a.m[2][1] += yz;
}
template <class R>
RC_HD SphGpuVec3<R> column(const SphGpuMat3<R>& a, int j) {
  return {a.m[0][j], a.m[1][j], a.m[2][j]};
}
template <class R>
RC_HD void setColumn(SphGpuMat3<R>& a, int j, const SphGpuVec3<R>& v) {
  a.m[0][j] = v.x, a.m[1][j] = v.y, a.m[2][j] = v.z;
}

/// Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations: s = V diag(lambda) V^T with
/// lambda descending and V a rotation.
template <class R>
RC_HD void symmetricEigen(SphGpuMat3<R> s, SphGpuMat3<R>& v, R lambda[3]) {
  v = identityMat3<R>();
  for (int sweep = 0; sweep < 8; ++sweep) {
    const R off = s.m[0][1] * s.m[0][1] + s.m[0][2] * s.m[0][2] + s.m[1][2] * s.m[1][2];
    const R diag = s.m[0][0] * s.m[0][0] + s.m[1][1] * s.m[1][1] + s.m[2][2] * s.m[2][2];
    if (!(off > R(1e-30) * diag) || off == R(0)) break;
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        const R apq = s.m[p][q];
        if (apq == R(0)) continue;
        // Rotation that zeroes s_pq (Golub & Van Loan 8.4.2).
        const R tau = (s.m[q][q] - s.m[p][p]) / (R(2) * apq);
        const R t = (tau >= R(0) ? R(1) : R(-1)) / (sphAbs(tau) + sphSqrt(R(1) + tau * tau));
        const R c = R(1) / sphSqrt(R(1) + t * t), sn = t * c;
        for (int k = 0; k < 3; ++k) {  // s <- s J
          const R skp = s.m[k][p], skq = s.m[k][q];
          s.m[k][p] = c * skp - sn * skq;
          s.m[k][q] = sn * skp + c * skq;
        }
        for (int k = 0; k < 3; ++k) {  // s <- J^T s
          const R spk = s.m[p][k], sqk = s.m[q][k];
          s.m[p][k] = c * spk - sn * sqk;
          s.m[q][k] = sn * spk + c * sqk;
        }
        for (int k = 0; k < 3; ++k) {  // v <- v J
          const R vkp = v.m[k][p], vkq = v.m[k][q];
          v.m[k][p] = c * vkp - sn * vkq;
          v.m[k][q] = sn * vkp + c * vkq;
        }
      }
  }
  for (int k = 0; k < 3; ++k) lambda[k] = s.m[k][k];
  // Sort descending (swapping columns; a swap flips the determinant, fixed below).
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2 - a; ++b)
      if (lambda[b] < lambda[b + 1]) {
        const R l = lambda[b];
        lambda[b] = lambda[b + 1];
        lambda[b + 1] = l;
        const SphGpuVec3<R> cb = column(v, b);
        setColumn(v, b, column(v, b + 1));
        setColumn(v, b + 1, cb);
      }
  if (determinant(v) < R(0)) setColumn(v, 2, -column(v, 2));
}

/// Reflection-safe SVD a = U diag(sigma) V^T with U, V rotations and sigma descending except that the
/// smallest carries the sign of det a (as rotationSvd of the CPU solid, so that R = U V^T is a rotation
/// (8.24)). From the eigen-decomposition of a^T a; columns of U of vanishing singular values are completed.
template <class R>
RC_HD void rotationSvd3(const SphGpuMat3<R>& a, SphGpuMat3<R>& u, R sigma[3], SphGpuMat3<R>& v) {
  R lambda[3];
  symmetricEigen(transposed(a) * a, v, lambda);
  SphGpuVec3<R> av[3];
  for (int k = 0; k < 3; ++k) {
    av[k] = a * column(v, k);
    sigma[k] = sphSqrt(sphMax(lambda[k], R(0)));
  }
  // u0, u1 from a v / sigma (or any orthonormal completion), u2 = u0 x u1; then sigma2 = u2 . a v2 is signed.
  SphGpuVec3<R> u0 = av[0];
  R n0 = sphSqrt(dot(u0, u0));
  if (!(n0 > R(0))) {
    u0 = column(v, 0);
    n0 = R(1);
  }
  u0 = (R(1) / n0) * u0;
  SphGpuVec3<R> u1 = av[1] - dot(av[1], u0) * u0;
  R n1 = sphSqrt(dot(u1, u1));
  if (!(n1 > R(1e-12) * (n0 + R(1e-30)))) {  // rank < 2: any unit vector orthogonal to u0
    const SphGpuVec3<R> e = sphAbs(u0.x) < R(0.6) ? vec3<R>(1, 0, 0) : vec3<R>(0, 1, 0);
    u1 = e - dot(e, u0) * u0;
    n1 = sphSqrt(dot(u1, u1));
  }
  u1 = (R(1) / n1) * u1;
  const SphGpuVec3<R> u2 = cross(u0, u1);
  setColumn(u, 0, u0);
  setColumn(u, 1, u1);
  setColumn(u, 2, u2);
  sigma[2] = dot(u2, av[2]);
}

}  // namespace rc
