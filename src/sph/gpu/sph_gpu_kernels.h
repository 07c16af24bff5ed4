// Per-particle SPH functions shared by the CUDA kernels (sph_gpu_solver.cu, float) and the host driver
// (SphGpuHostSolver, float or double): the formulas of SphFluidSolver (weakly compressible fluid, 8.1.4)
// and of SphElasticSolid's explicit goal-position model (8.2), on particles sorted by grid cell.
#pragma once

#include <cstdint>

#include "relaxed_connectivity/sph/gpu/sph_gpu_math.h"

namespace rc {

/// Particle kinds as SphParticleKind.
constexpr uint32_t kSphGpuFluid = 0, kSphGpuStaticBoundary = 1, kSphGpuMovingBoundary = 2;
/// material = kind | phase << 8 (phase 0: fluid, else the elastic solid of that id).
RC_HD uint32_t sphKind(uint32_t material) {
  return material & 0xFFu;
}
RC_HD uint32_t sphPhase(uint32_t material) {
  return material >> 8;
}

/// Most neighbours of one solid particle (same solid) the lattice assignment holds; more raise
/// kSphGpuNeighborOverflow and the rest are ignored.
constexpr int kSphGpuMaxSolidNeighbors = 128;
/// Neighbour masks: a run of more candidates than this marks the particle as unlisted (it scans the cells).
constexpr uint32_t kSphGpuMaskBits = 64;
constexpr uint32_t kSphGpuUnlisted = 0x80000000u;  // flag bit of neighbor_count
/// Error flags raised by the per-particle functions.
constexpr uint32_t kSphGpuNeighborOverflow = 1u, kSphGpuNonFinite = 2u;

/// Fluid parameters and the uniform grid (cells of size >= h, x fastest).
template <class R>
struct SphGpuParams {
  R h, h2, inv_h;
  R poly6_coeff, spiky_coeff, viscosity_coeff;  // appendix C, SphKernels
  R rest_density, stiffness, gamma, negative_pressure_scale;
  R viscosity, xsph;
  SphGpuVec3<R> gravity;
  int poly6_pressure;  // 1: poly6 gradient in (8.17), 0: spiky
  R grid_lo[3];
  R inv_cell;
  int dims[3];
  int num_planes;
  int max_phase;  // phases 1..max_phase have SphGpuSolidParams
};

/// One elastic solid (goal-position model, 8.29-8.31), indexed by its phase.
template <class R>
struct SphGpuSolidParams {
  int active;           // 0: phase without a solid
  SphGpuMat3<R> basis;  // B of (8.20)
  SphGpuMat3<R> inverse_basis;
  SphGpuMat3<R> gram;       // B^T B
  R spacing2;               // d^2
  R cell_volume;            // V
  R goal_stiffness;         // K_e (8.31), per unit mass
  R deformation_allowance;  // s (8.30)
  int min_neighbors;
};

/// Half-space x . normal >= offset (normalised), as SphPlane.
template <class R>
struct SphGpuPlane {
  SphGpuVec3<R> normal;
  R offset, restitution, friction;
};

/// The sorted particle arrays of one system (all pointers of the same memory space).
template <class R>
struct SphGpuState {
  uint32_t n;
  SphGpuVec4<R>* pos_mass;       // x, y, z, mass
  SphGpuVec4<R>* velocity;       // state velocity
  SphGpuVec4<R>* eval_vel;       // velocity of the force evaluation (predicted); w: density
  R* pressure;                   // (8.15)-(8.16)
  R* pressure_term;              // p / rho^2
  uint32_t* material;            // kind | phase << 8
  SphGpuVec4<R>* acceleration;   // w unused
  SphGpuVec4<R>* xsph;           // (8.19) velocity correction
  SphGpuVec4<R>* elastic_force;  // accumulated goal forces (8.31)
  SphGpuMat3<R>* transform;      // A_i of the last fit (8.23), starts at the lattice orientation
  R* strain;                     // max |sigma - 1| of the last fit (0 unmatched)
  const uint32_t* cell_start;    // num_cells + 1 entries
  // Neighbours found by the density pass (null: every pass scans the cells): per sorted particle s and run
  // r of sphForEachRun a bit mask of the run's candidates that are neighbours, at neighbor_masks[r * n + s];
  // neighbor_count[s]: the number of neighbours, with the flag kSphGpuUnlisted where a run is longer than
  // kSphGpuMaskBits (the masks are then not used).
  uint64_t* neighbor_masks;
  uint32_t* neighbor_count;
  uint32_t* error_flags;
};

template <class R>
RC_HD void sphRaise(uint32_t* flags, uint32_t bit) {
#ifdef __CUDA_ARCH__
  atomicOr(flags, bit);
#else
  __atomic_fetch_or(flags, bit, __ATOMIC_RELAXED);
#endif
}

/// Grid coordinate of x along axis a, clamped to the grid.
template <class R>
RC_HD int sphCellCoordinate(const SphGpuParams<R>& p, R x, int a) {
  const R c = (x - p.grid_lo[a]) * p.inv_cell;
  if (!(c >= R(0))) return 0;  // also NaN
  const int i = int(c);
  return i < p.dims[a] ? i : p.dims[a] - 1;
}

template <class R>
RC_HD uint32_t sphCellOf(const SphGpuParams<R>& p, const SphGpuVec4<R>& x) {
  const int cx = sphCellCoordinate(p, x.x, 0), cy = sphCellCoordinate(p, x.y, 1),
            cz = sphCellCoordinate(p, x.z, 2);
  return (uint32_t(cz) * uint32_t(p.dims[1]) + uint32_t(cy)) * uint32_t(p.dims[0]) + uint32_t(cx);
}

/// Calls fn(r, begin, end) for the runs [begin, end) of sorted particles in the 27 cells around x: run
/// r = 3 (dz + 1) + (dy + 1) covers the cells dx = -1..1 (runs outside the grid are skipped).
template <class R, class Fn>
RC_HD void sphForEachRun(const SphGpuParams<R>& p, const uint32_t* cell_start, const SphGpuVec4<R>& x,
                         Fn&& fn) {
  const int cx = sphCellCoordinate(p, x.x, 0), cy = sphCellCoordinate(p, x.y, 1),
            cz = sphCellCoordinate(p, x.z, 2);
  const int x0 = cx > 0 ? cx - 1 : 0, x1 = cx + 1 < p.dims[0] ? cx + 1 : cx;
  for (int z = cz - 1; z <= cz + 1; ++z) {
    if (z < 0 || z >= p.dims[2]) continue;
    for (int y = cy - 1; y <= cy + 1; ++y) {
      if (y < 0 || y >= p.dims[1]) continue;
      const uint32_t row = (uint32_t(z) * uint32_t(p.dims[1]) + uint32_t(y)) * uint32_t(p.dims[0]);
      fn(3 * (z - cz + 1) + (y - cy + 1), cell_start[row + uint32_t(x0)], cell_start[row + uint32_t(x1) + 1]);
    }
  }
}

/// Calls fn(j) for every sorted particle j in the 27 cells around x.
template <class R, class Fn>
RC_HD void sphForEachCandidate(const SphGpuParams<R>& p, const uint32_t* cell_start, const SphGpuVec4<R>& x,
                               Fn&& fn) {
  sphForEachRun(p, cell_start, x, [&](int, uint32_t begin, uint32_t end) {
    for (uint32_t j = begin; j < end; ++j) fn(j);
  });
}

RC_HD int sphLowestBit(uint64_t m) {
#ifdef __CUDA_ARCH__
  return __ffsll((long long)m) - 1;
#else
  return __builtin_ctzll(m);
#endif
}

/// Calls fn(j) for every neighbour j (d < h, j != s) of sorted particle s, in cell order: from the masks of
/// the density pass where it has them, else by scanning the cells.
template <class R, class Fn>
RC_HD void sphForEachNeighbor(const SphGpuParams<R>& p, const SphGpuState<R>& st, uint32_t s, Fn&& fn) {
  const SphGpuVec4<R> xi = st.pos_mass[s];
  if (st.neighbor_masks && !(st.neighbor_count[s] & kSphGpuUnlisted)) {
    sphForEachRun(p, st.cell_start, xi, [&](int r, uint32_t begin, uint32_t) {
      for (uint64_t m = st.neighbor_masks[size_t(r) * st.n + s]; m; m &= m - 1) fn(begin + sphLowestBit(m));
    });
    return;
  }
  sphForEachCandidate(p, st.cell_start, xi, [&](uint32_t j) {
    const SphGpuVec4<R> xj = st.pos_mass[j];
    const R dx = xj.x - xi.x, dy = xj.y - xi.y, dz = xj.z - xi.z;
    if (dx * dx + dy * dy + dz * dz < p.h2 && j != s) fn(j);
  });
}

/// Pressure (8.15) with the scaled negative part (8.16).
template <class R>
RC_HD R sphPressureOf(const SphGpuParams<R>& p, R rho) {
  const R ratio = rho / p.rest_density;
  const R value = p.stiffness * ((p.gamma == R(1) ? ratio : sphPow(ratio, p.gamma)) - R(1));
  return value >= R(0) ? value : p.negative_pressure_scale * value;
}

/// Density (8.4, self included), pressure and p / rho^2 of sorted particle s; boundary pressures >= 0.
/// Records the neighbour masks (if the state has them).
template <class R>
RC_HD void sphDensity(const SphGpuParams<R>& p, const SphGpuState<R>& st, uint32_t s) {
  const SphGpuVec4<R> xi = st.pos_mass[s];
  R sum = R(0);
  uint32_t count = 0;
  bool listed = true;
  sphForEachRun(p, st.cell_start, xi, [&](int r, uint32_t begin, uint32_t end) {
    uint64_t mask = 0;
    for (uint32_t j = begin; j < end; ++j) {
      const SphGpuVec4<R> xj = st.pos_mass[j];
      const R dx = xj.x - xi.x, dy = xj.y - xi.y, dz = xj.z - xi.z;
      const R d2 = dx * dx + dy * dy + dz * dz;
      if (d2 < p.h2 && j != s) {
        const R q = R(1) - d2 / p.h2;
        sum += xj.w * (q * q * q);
        ++count;
        if (j - begin < kSphGpuMaskBits) {
          mask |= uint64_t(1) << (j - begin);
        } else {
          listed = false;
        }
      }
    }
    if (st.neighbor_masks)
      st.neighbor_masks[size_t(r) * st.n + s] = mask;  // runs outside the grid: never read
  });
  if (st.neighbor_masks) st.neighbor_count[s] = listed ? count : (count | kSphGpuUnlisted);
  const R rho = p.poly6_coeff * (xi.w + sum);  // (8.4)
  R pressure = sphPressureOf(p, rho);
  if (sphKind(st.material[s]) != kSphGpuFluid && pressure < R(0)) pressure = R(0);  // walls never pull
  st.eval_vel[s].w = rho;
  st.pressure[s] = pressure;
  st.pressure_term[s] = pressure / (rho * rho);
}

/// Acceleration (pressure 8.17, viscosity 8.18, gravity) and XSPH correction (8.19) of sorted particle s;
/// zero for boundary particles. Returns the number of neighbours.
template <class R>
RC_HD uint32_t sphForce(const SphGpuParams<R>& p, const SphGpuState<R>& st, uint32_t s) {
  if (sphKind(st.material[s]) != kSphGpuFluid) {
    st.acceleration[s] = {R(0), R(0), R(0), R(0)};
    st.xsph[s] = {R(0), R(0), R(0), R(0)};
    return 0;
  }
  const SphGpuVec4<R> xi = st.pos_mass[s], vi = st.eval_vel[s];
  const R mi = xi.w, rhoi = vi.w, pti = st.pressure_term[s];
  const R spiky_grad = R(-3) * p.spiky_coeff * p.inv_h;  // w^'(d) = spiky_grad (1 - d/h)^2
  const R poly6_grad = R(-6) * p.poly6_coeff / p.h2;     // grad W = poly6_grad q^2 r
  const R visc = p.viscosity * p.viscosity_coeff;
  SphGpuVec3<R> force = {R(0), R(0), R(0)}, smooth = {R(0), R(0), R(0)};
  uint32_t count = 0;
  sphForEachNeighbor(p, st, s, [&](uint32_t j) {
    const SphGpuVec4<R> xj = st.pos_mass[j];
    const SphGpuVec3<R> r = {xi.x - xj.x, xi.y - xj.y, xi.z - xj.z};
    const R d2 = dot(r, r);
    ++count;
    const SphGpuVec4<R> vj = st.eval_vel[j];
    const R d = sphSqrt(d2);
    const R mm = mi * xj.w;
    const R u = R(1) - d * p.inv_h;
    const R q = R(1) - d2 / p.h2;
    const R ptj = st.pressure_term[j];
    // -m_i m_j (p_i/rho_i^2 + p_j/rho_j^2) grad W(r_ij)   (8.17)
    if (p.poly6_pressure) {
      force -= ((pti + ptj) * mm * (poly6_grad * q * q)) * r;
    } else if (d > R(0)) {
      force -= ((pti + ptj) * mm * (spiky_grad * u * u / d)) * r;
    }
    const SphGpuVec3<R> dv = {vj.x - vi.x, vj.y - vi.y, vj.z - vi.z};
    force += (visc * mm / (rhoi * vj.w) * u) * dv;  // (8.12), (8.18)
    if (sphKind(st.material[j]) == kSphGpuFluid)
      smooth += (xj.w / (R(0.5) * (rhoi + vj.w)) * p.poly6_coeff * q * q * q) * dv;  // (8.19)
  });
  const SphGpuVec3<R> a = (R(1) / mi) * force + p.gravity;
  st.acceleration[s] = vec4(a, R(0));
  st.xsph[s] = vec4(p.xsph * smooth, R(0));
  return count;
}

/// Lattice index packed into 30 bits (10 per coordinate, offset 512); the origin is kSphGpuOriginKey.
RC_HD uint32_t sphLatticeKey(int x, int y, int z) {
  const auto c = [](int v) { return uint32_t(v + 512 < 0 ? 0 : (v + 512 > 1023 ? 1023 : v + 512)); };
  return (c(x) << 20) | (c(y) << 10) | c(z);
}
constexpr uint32_t kSphGpuOriginKey = (512u << 20) | (512u << 10) | 512u;

/// The lattice point B n nearest to the lattice coordinates c (SphLattice::nearestIndexOfCoordinates):
/// rounding, refined over the 27 neighbouring indices when outside the ball of radius d/2.
template <class R>
RC_HD uint32_t sphNearestLatticeKey(const SphGpuSolidParams<R>& solid, const SphGpuVec3<R>& c, R& sq_dist) {
  const auto round = [](R x) { return int(x + (x >= R(0) ? R(0.5) : R(-0.5))); };
  const int nx = round(c.x), ny = round(c.y), nz = round(c.z);
  const R ex = c.x - R(nx), ey = c.y - R(ny), ez = c.z - R(nz);
  const SphGpuMat3<R>& g = solid.gram;
  const auto norm2 = [&g](R x, R y, R z) {
    return g.m[0][0] * x * x + g.m[1][1] * y * y + g.m[2][2] * z * z +
           R(2) * (g.m[0][1] * x * y + g.m[0][2] * x * z + g.m[1][2] * y * z);
  };
  int bx = nx, by = ny, bz = nz;
  R best = norm2(ex, ey, ez);
  if (best >= R(0.25) * solid.spacing2) {
    for (int dk = -1; dk <= 1; ++dk)
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          const R d2 = norm2(ex - R(di), ey - R(dj), ez - R(dk));
          if (d2 < best) {
            best = d2;
            bx = nx + di, by = ny + dj, bz = nz + dk;
          }
        }
  }
  sq_dist = best;
  return sphLatticeKey(bx, by, bz);
}

/// B n of a packed lattice index.
template <class R>
RC_HD SphGpuVec3<R> sphLatticePoint(const SphGpuSolidParams<R>& solid, uint32_t key) {
  const R n[3] = {R(int((key >> 20) & 1023u) - 512), R(int((key >> 10) & 1023u) - 512),
                  R(int(key & 1023u) - 512)};
  return solid.basis * vec3(n[0], n[1], n[2]);
}

/// Goal-position forces (8.21-8.25, 8.29-8.31) of the neighbourhood of solid particle s with the per-
/// neighbourhood linear and angular momentum correction (8.32-8.33) as SphElasticSolid (explicit model):
/// lattice assignment from the previous transform A_i with one particle per lattice point (the closest; ties
/// to the lower sorted index), fit A_i = (sum W r l^T)(sum W l l^T)^-1 (8.23), rotation and goal stretch
/// from its SVD (8.24, 8.30), F_j = K_e m_i V W_ij / 2 (g_ij - r_ij) (8.31), F_i = -sum F_j, then the torque
/// about the weighted centre is removed. add_force(j, f) accumulates (atomically) the force on j.
/// Updates transform[s] (clamped singular values) and strain[s].
template <class R, class AddForce>
RC_HD void sphElasticNeighborhood(const SphGpuParams<R>& p, const SphGpuSolidParams<R>* solids,
                                  const SphGpuState<R>& st, uint32_t s, AddForce&& add_force) {
  const uint32_t material = st.material[s];
  const uint32_t phase = sphPhase(material);
  if (sphKind(material) != kSphGpuFluid || phase == 0 || int(phase) > p.max_phase) return;
  const SphGpuSolidParams<R>& solid = solids[phase];
  if (!solid.active) return;
  const SphGpuVec4<R> xi4 = st.pos_mass[s];
  const SphGpuVec3<R> xi = xyz(xi4);
  const SphGpuMat3<R> to_coordinates = solid.inverse_basis * inverted(st.transform[s]);  // B^-1 A^-1
  uint32_t neighbor[kSphGpuMaxSolidNeighbors], key[kSphGpuMaxSolidNeighbors];  // (local memory: kept small)
  int nn = 0;
  bool overflow = false;
  sphForEachNeighbor(p, st, s, [&](uint32_t j) {
    if (st.material[j] != material) return;
    if (nn == kSphGpuMaxSolidNeighbors) {
      overflow = true;
      return;
    }
    neighbor[nn++] = j;
  });
  for (int k = 0; k < nn; ++k) {  // (8.21), outside the neighbour loop: no divergence between the lanes
    R unused;
    key[k] = sphNearestLatticeKey(solid, to_coordinates * (xyz(st.pos_mass[neighbor[k]]) - xi), unused);
  }
  // Squared distance of neighbour k to its lattice point (recomputed where two neighbours compete).
  const auto lattice_d2 = [&](int k) {
    R d2;
    sphNearestLatticeKey(solid, to_coordinates * (xyz(st.pos_mass[neighbor[k]]) - xi), d2);
    return d2;
  };
  if (overflow) sphRaise<R>(st.error_flags, kSphGpuNeighborOverflow);
  // One particle per lattice point (8.21): a neighbour loses its point to a closer one; the origin is the
  // centre's. Lost neighbours are marked by setting the key's top bit. Only keys whose bucket (of 128) occurs
  // twice are compared pairwise: the lattice offsets in [-2, 2]^3 (all 42 of an undeformed fcc neighbourhood
  // with h < 2 d) have a bucket each, the others share the last three.
  constexpr uint32_t kLost = 0x80000000u;
  const auto bucket = [](uint32_t k) {
    const uint32_t x = ((k >> 20) & 1023u) - 510u, y = ((k >> 10) & 1023u) - 510u, z = (k & 1023u) - 510u;
    if (x < 5u && y < 5u && z < 5u) return (x * 5u + y) * 5u + z;  // 0..124
    return 125u + ((k * 2654435761u) >> 30) % 3u;
  };
  uint64_t seen[2] = {0, 0}, twice[2] = {0, 0};
  for (int k = 0; k < nn; ++k) {
    const uint32_t b = bucket(key[k]);
    const uint64_t bit = uint64_t(1) << (b & 63u);
    if (b & 64u) {
      twice[1] |= seen[1] & bit;
      seen[1] |= bit;
    } else {
      twice[0] |= seen[0] & bit;
      seen[0] |= bit;
    }
  }
  for (int k = 0; k < nn; ++k) {
    const uint32_t kk = key[k] & ~kLost;
    if (kk == kSphGpuOriginKey) {
      key[k] |= kLost;
      continue;
    }
    const uint32_t b = bucket(kk);
    if (!(((b & 64u) ? twice[1] : twice[0]) & (uint64_t(1) << (b & 63u)))) continue;
    for (int o = k + 1; o < nn; ++o) {
      if ((key[o] & ~kLost) != kk) continue;
      if (lattice_d2(o) < lattice_d2(k)) {
        key[k] |= kLost;
      } else {
        key[o] |= kLost;
      }
    }
  }
  // Fit (8.23), and the weighted sums that give the torque and inertia of the momentum correction (8.32).
  const R w_centre = p.poly6_coeff;
  R w_sum = w_centre;
  SphGpuVec3<R> c = {R(0), R(0), R(0)}, sum_l = {R(0), R(0), R(0)};
  SphGpuMat3<R> rl = zeroMat3<R>(), ll = zeroMat3<R>(), rr = zeroMat3<R>();
  int count = 0;
  for (int k = 0; k < nn; ++k) {
    if (key[k] & kLost) continue;
    const SphGpuVec3<R> r = xyz(st.pos_mass[neighbor[k]]) - xi;
    const R q = R(1) - dot(r, r) / p.h2;
    const R w = p.poly6_coeff * q * q * q;
    const SphGpuVec3<R> l = sphLatticePoint(solid, key[k]);
    addOuter(rl, w, r, l);
    addOuter(ll, w, l, l);
    addOuter(rr, w, r, r);
    w_sum += w;
    c += w * r;
    sum_l += w * l;
    ++count;
  }
  st.strain[s] = R(0);
  if (count < solid.min_neighbors) return;
  const R scale = (ll.m[0][0] + ll.m[1][1] + ll.m[2][2]) / R(3);
  if (!(determinant(ll) > R(1e-6) * scale * scale * scale)) return;  // (near) planar neighbourhood
  const SphGpuMat3<R> a = rl * inverted(ll);
  SphGpuMat3<R> u, v;
  R sigma[3];
  rotationSvd3(a, u, sigma, v);  // R = U V^T (8.24)
  const R allowance = solid.deformation_allowance;
  R sv[3], clamped[3];
  for (int k = 0; k < 3; ++k) {
    sv[k] = sphMax(allowance * sigma[k] + (R(1) - allowance), R(0.05));  // (8.30)
    clamped[k] = sphMin(sphMax(sigma[k], R(0.25)), R(4));
  }
  const R volume_factor = sphCbrt(sv[0] * sv[1] * sv[2]);
  SphGpuMat3<R> goal, next;  // U S V^T (8.29), U clamp(sigma) V^T (the next assignment's A_i)
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      R g = R(0), t = R(0);
      for (int k = 0; k < 3; ++k) {
        g += u.m[i][k] * (sv[k] / volume_factor) * v.m[j][k];
        t += u.m[i][k] * clamped[k] * v.m[j][k];
      }
      goal.m[i][j] = g;
      next.m[i][j] = t;
    }
  st.transform[s] = next;
  st.strain[s] = sphMax(sphAbs(sigma[0] - R(1)), sphAbs(sigma[2] - R(1)));
  // Goal forces (8.31) f_k = a W_k (G l_k - r_k), a = K_e m_i V / 2, on the neighbours and -sum f_k on the
  // centre. Their torque about the weighted centre c is sum_k r_k x f_k = a axial(sum_k W_k r_k (G l_k)^T)
  // (sum_k r_k x r_k = 0; the centre's lever -c cancels -c x sum f_k), and the weighted inertia about c
  // follows from sum W r r^T, so one pass over the neighbours applies the corrected forces.
  const R a_e = R(0.5) * solid.goal_stiffness * xi4.w * solid.cell_volume;
  const SphGpuVec3<R> sum_r = c;
  c = (R(1) / w_sum) * c;  // relative to x_i
  const SphGpuVec3<R> centre_force = a_e * (sum_r - goal * sum_l);
  const SphGpuMat3<R> moment = rl * transposed(goal);  // sum W r (G l)^T
  const SphGpuVec3<R> torque = a_e * vec3(moment.m[1][2] - moment.m[2][1], moment.m[2][0] - moment.m[0][2],
                                          moment.m[0][1] - moment.m[1][0]);
  const R w_neighbors = w_sum - w_centre;
  SphGpuMat3<R> spread = rr;  // sum W (r - c)(r - c)^T
  addOuter(spread, R(-1), sum_r, c);
  addOuter(spread, R(-1), c, sum_r);
  addOuter(spread, w_neighbors, c, c);
  SphGpuMat3<R> inertia = zeroMat3<R>();
  addInertia(inertia, w_centre, -c);
  const R trace = spread.m[0][0] + spread.m[1][1] + spread.m[2][2];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) inertia.m[i][j] += (i == j ? trace : R(0)) - spread.m[i][j];
  // (8.32)-(8.33): forces w_k omega x (x_k - c) with I omega = -tau sum to zero and remove the torque.
  const R det = determinant(inertia);
  const R size = inertia.m[0][0] + inertia.m[1][1] + inertia.m[2][2];
  SphGpuVec3<R> omega = {R(0), R(0), R(0)};
  if (det > R(1e-12) * size * size * size) omega = -(inverted(inertia) * torque);
  // Scatter starting at a neighbour that depends on s, so that the threads of a warp (neighbouring particles
  // with similar rows) rarely add to the same particle at once.
  for (int e = 0, k = nn > 0 ? int(s % uint32_t(nn)) : 0; e < nn; ++e, k = k + 1 == nn ? 0 : k + 1) {
    if (key[k] & kLost) continue;
    const SphGpuVec3<R> r = xyz(st.pos_mass[neighbor[k]]) - xi;
    const R q = R(1) - dot(r, r) / p.h2;
    const R w = p.poly6_coeff * q * q * q;
    const SphGpuVec3<R> f = (a_e * w) * (goal * sphLatticePoint(solid, key[k]) - r) + w * cross(omega, r - c);
    add_force(neighbor[k], f);
  }
  add_force(s, centre_force + w_centre * cross(omega, -c));
}

/// Adds the elastic force to the acceleration of fluid-kind particle s (after sphElasticNeighborhood).
template <class R>
RC_HD void sphAddElasticAcceleration(const SphGpuState<R>& st, uint32_t s) {
  if (sphKind(st.material[s]) != kSphGpuFluid) return;
  const SphGpuVec4<R> f = st.elastic_force[s];
  const R inv_m = R(1) / st.pos_mass[s].w;
  SphGpuVec4<R>& a = st.acceleration[s];
  a.x += inv_m * f.x, a.y += inv_m * f.y, a.z += inv_m * f.z;
}

/// Pushes x back onto the planes it penetrates, reflecting (restitution) and damping (friction) the
/// velocity, as SphFluidSolver.
template <class R>
RC_HD void sphCollide(const SphGpuPlane<R>* planes, int num_planes, SphGpuVec3<R>& x, SphGpuVec3<R>& v) {
  for (int k = 0; k < num_planes; ++k) {
    const SphGpuPlane<R>& plane = planes[k];
    const R depth = plane.offset - dot(plane.normal, x);
    if (depth <= R(0)) continue;
    x += depth * plane.normal;
    const R vn = dot(plane.normal, v);
    if (vn < R(0)) {
      const SphGpuVec3<R> tangential = v - vn * plane.normal;
      v = (R(1) - plane.friction) * tangential - (plane.restitution * vn) * plane.normal;
    }
  }
}

/// The result of the first half of velocity Verlet for one particle (sphKickDriftOf).
template <class R>
struct SphGpuDrift {
  SphGpuVec4<R> pos_mass, velocity, eval_vel;
  bool finite;
};

/// First half of velocity Verlet for the particle at i of `st`: kick, drift with XSPH, plane collisions, and
/// the predicted velocity of the coming force evaluation (fluid); moving boundaries drift with their
/// velocity; static ones stay (evaluation velocity 0).
template <class R>
RC_HD SphGpuDrift<R> sphKickDriftOf(const SphGpuParams<R>& p, const SphGpuPlane<R>* planes,
                                    const SphGpuState<R>& st, uint32_t i, R dt) {
  const uint32_t kind = sphKind(st.material[i]);
  const SphGpuVec4<R> x4 = st.pos_mass[i], v4 = st.velocity[i];
  SphGpuDrift<R> d = {x4, v4, {R(0), R(0), R(0), R(0)}, true};
  if (kind == kSphGpuStaticBoundary) return d;
  SphGpuVec3<R> x = xyz(x4), v = xyz(v4);
  if (kind == kSphGpuMovingBoundary) {
    d.pos_mass = vec4(x + dt * v, x4.w);
    d.eval_vel = vec4(v, R(0));
    return d;
  }
  const SphGpuVec3<R> a = xyz(st.acceleration[i]);
  v += (R(0.5) * dt) * a;
  x += dt * (v + xyz(st.xsph[i]));
  sphCollide(planes, p.num_planes, x, v);
  d.finite = dot(x, x) < R(1e30) && dot(v, v) < R(1e30);
  d.pos_mass = vec4(x, x4.w);
  d.velocity = vec4(v, R(0));
  d.eval_vel = vec4(v + (R(0.5) * dt) * a, R(0));
  return d;
}

/// sphKickDriftOf in place.
template <class R>
RC_HD void sphKickDrift(const SphGpuParams<R>& p, const SphGpuPlane<R>* planes, const SphGpuState<R>& st,
                        uint32_t s, R dt) {
  const SphGpuDrift<R> d = sphKickDriftOf(p, planes, st, s, dt);
  if (!d.finite) sphRaise<R>(st.error_flags, kSphGpuNonFinite);
  st.pos_mass[s] = d.pos_mass;
  st.velocity[s] = d.velocity;
  st.eval_vel[s] = d.eval_vel;
}

/// Second half kick with the new acceleration (fluid kind).
template <class R>
RC_HD void sphFinalKick(const SphGpuState<R>& st, uint32_t s, R dt) {
  if (sphKind(st.material[s]) != kSphGpuFluid) return;
  const SphGpuVec4<R> a = st.acceleration[s];
  SphGpuVec4<R>& v = st.velocity[s];
  v.x += R(0.5) * dt * a.x, v.y += R(0.5) * dt * a.y, v.z += R(0.5) * dt * a.z;
}

}  // namespace rc
