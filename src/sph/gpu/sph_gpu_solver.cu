#include "relaxed_connectivity/sph/gpu/sph_gpu_solver.h"

#include <cuda_runtime.h>

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace rc {

namespace {

using Vec4 = SphGpuVec4<float>;
using Mat3 = SphGpuMat3<float>;

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess)
    throw std::runtime_error(std::string("SphGpuSolver: ") + what + ": " + cudaGetErrorString(e));
}

/// Device array that only grows.
template <class T>
struct DeviceArray {
  T* ptr = nullptr;
  size_t count = 0;
  DeviceArray() = default;
  DeviceArray(const DeviceArray&) = delete;
  ~DeviceArray() {
    if (ptr) cudaFree(ptr);
  }
  void resize(size_t n, const char* name) {
    if (n <= count) return;
    if (ptr) cudaFree(ptr);
    ptr = nullptr;
    check(cudaMalloc(&ptr, (n ? n : 1) * sizeof(T)), name);
    count = n;
  }
  void upload(const std::vector<T>& v, const char* name) {
    resize(v.size(), name);
    check(cudaMemcpy(ptr, v.data(), v.size() * sizeof(T), cudaMemcpyHostToDevice), name);
  }
  void download(std::vector<T>& v, size_t n, const char* name) const {
    v.resize(n);
    check(cudaMemcpy(v.data(), ptr, n * sizeof(T), cudaMemcpyDeviceToHost), name);
  }
};

constexpr int kBlock = 128;
unsigned blocksFor(size_t n) {
  return unsigned((n + kBlock - 1) / kBlock);
}

__global__ void cellKeysKernel(SphGpuParams<float> p, const Vec4* pos, uint32_t* keys, uint32_t* index,
                               uint32_t n) {
  const uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s >= n) return;
  keys[s] = sphCellOf(p, pos[s]);
  index[s] = s;
}

/// cell_start[c] = first sorted position with key >= c (c in [0, cells]).
__global__ void cellStartKernel(const uint32_t* keys, uint32_t n, uint32_t* cell_start, uint32_t cells) {
  const uint32_t c = blockIdx.x * blockDim.x + threadIdx.x;
  if (c > cells) return;
  uint32_t lo = 0, hi = n;
  while (lo < hi) {
    const uint32_t mid = (lo + hi) >> 1;
    if (keys[mid] < c) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  cell_start[c] = lo;
}

struct SortedArrays {
  Vec4* pos_mass;
  Vec4* velocity;
  Vec4* eval_vel;
  uint32_t* material;
  uint32_t* id;
  Mat3* transform;
};

__global__ void gatherKernel(SortedArrays src, SortedArrays dst, const uint32_t* order, uint32_t n) {
  const uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s >= n) return;
  const uint32_t i = order[s];
  dst.pos_mass[s] = src.pos_mass[i];
  dst.velocity[s] = src.velocity[i];
  dst.eval_vel[s] = src.eval_vel[i];
  const uint32_t material = src.material[i];
  dst.material[s] = material;
  dst.id[s] = src.id[i];
  if (sphPhase(material) != 0) dst.transform[s] = src.transform[i];  // only solids read it
}

/// Fused kick-drift and cell keys: the key of particle i after its kick-drift (sphKickDriftOf, recomputed by
/// kickDriftGatherKernel with the same inputs, so both see the same position).
__global__ void kickDriftKeysKernel(SphGpuParams<float> p, const SphGpuPlane<float>* planes,
                                    SphGpuState<float> st, float dt, uint32_t* keys, uint32_t* index) {
  const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= st.n) return;
  keys[i] = sphCellOf(p, sphKickDriftOf(p, planes, st, i, dt).pos_mass);
  index[i] = i;
}

/// Fused kick-drift and reorder: sorted position s receives the kick-drifted particle order[s] of `src`, and
/// solid_flag[s] = 1 for the particles of an active solid (the input of the solid list).
__global__ void kickDriftGatherKernel(SphGpuParams<float> p, const SphGpuPlane<float>* planes,
                                      SphGpuState<float> src, const uint32_t* src_id, SortedArrays dst,
                                      const uint32_t* order, float dt, const SphGpuSolidParams<float>* solids,
                                      uint32_t* solid_flag) {
  const uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s >= src.n) return;
  const uint32_t i = order[s];
  const SphGpuDrift<float> d = sphKickDriftOf(p, planes, src, i, dt);
  if (!d.finite) sphRaise<float>(src.error_flags, kSphGpuNonFinite);
  dst.pos_mass[s] = d.pos_mass;
  dst.velocity[s] = d.velocity;
  dst.eval_vel[s] = d.eval_vel;
  const uint32_t material = src.material[i];
  dst.material[s] = material;
  dst.id[s] = src_id[i];
  const uint32_t phase = sphPhase(material);
  if (phase != 0) dst.transform[s] = src.transform[i];  // only solids read it
  if (solid_flag)
    solid_flag[s] =
        sphKind(material) == kSphGpuFluid && phase != 0 && int(phase) <= p.max_phase && solids[phase].active;
}

__global__ void densityKernel(SphGpuParams<float> p, SphGpuState<float> st) {
  const uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s < st.n) sphDensity(p, st, s);
}

__global__ void forceKernel(SphGpuParams<float> p, SphGpuState<float> st) {
  const uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s < st.n) sphForce(p, st, s);
}

/// flag[s] = 1 for the solid particles (fluid kind, phase of an active solid).
__global__ void solidFlagKernel(const uint32_t* material, const SphGpuSolidParams<float>* solids,
                                int max_phase, uint32_t* flag, uint32_t n) {
  const uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s >= n) return;
  const uint32_t phase = sphPhase(material[s]);
  flag[s] =
      sphKind(material[s]) == kSphGpuFluid && phase != 0 && int(phase) <= max_phase && solids[phase].active;
}

__global__ void solidListKernel(const uint32_t* flag, const uint32_t* offset, uint32_t* list, uint32_t n) {
  const uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s < n && flag[s]) list[offset[s]] = s;
}

/// Goal forces of the neighbourhood of solid particle solid_list[t] scattered with vector atomics.
__device__ __forceinline__ void elasticOf(const SphGpuParams<float>& p,
                                          const SphGpuSolidParams<float>* solids,
                                          const SphGpuState<float>& st, const uint32_t* solid_list,
                                          uint32_t num_solid) {
  const uint32_t t = blockIdx.x * blockDim.x + threadIdx.x;
  if (t >= num_solid) return;
  const uint32_t s = solid_list[t];
  Vec4* force = st.elastic_force;
  sphElasticNeighborhood(p, solids, st, s, [force](uint32_t j, const SphGpuVec3<float>& f) {
#if __CUDA_ARCH__ >= 900
    atomicAdd(reinterpret_cast<float4*>(force + j), make_float4(f.x, f.y, f.z, 0.0f));  // one vector atomic
#else
    atomicAdd(&force[j].x, f.x);
    atomicAdd(&force[j].y, f.y);
    atomicAdd(&force[j].z, f.z);
#endif
  });
}

/// One thread per solid particle (sorted positions in `solid_list`).
__global__ void elasticKernel(SphGpuParams<float> p, const SphGpuSolidParams<float>* solids,
                              SphGpuState<float> st, const uint32_t* solid_list, uint32_t num_solid) {
  elasticOf(p, solids, st, solid_list, num_solid);
}

/// Forces, then the elastic acceleration (the elastic pass ran before) and the final kick; clears the
/// elastic forces of solid particles for the next evaluation. With `next_keys`: the cell keys of the coming
/// kick-drift (as kickDriftKeysKernel, from the state this pass leaves).
__global__ void forceFinishKernel(SphGpuParams<float> p, const SphGpuPlane<float>* planes,
                                  SphGpuState<float> st, float dt, int kick, int elastic, uint32_t* next_keys,
                                  uint32_t* next_index) {
  const uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s >= st.n) return;
  sphForce(p, st, s);
  if (elastic) {
    sphAddElasticAcceleration(st, s);
    if (sphPhase(st.material[s]) != 0) st.elastic_force[s] = {0.0f, 0.0f, 0.0f, 0.0f};
  }
  if (kick) sphFinalKick(st, s, dt);
  if (next_keys) {
    next_keys[s] = sphCellOf(p, sphKickDriftOf(p, planes, st, s, dt).pos_mass);
    next_index[s] = s;
  }
}

__global__ void finishKernel(SphGpuState<float> st, float dt, int kick, int elastic) {
  const uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s >= st.n) return;
  if (elastic) sphAddElasticAcceleration(st, s);
  if (kick) sphFinalKick(st, s, dt);
}

__global__ void kickDriftKernel(SphGpuParams<float> p, const SphGpuPlane<float>* planes,
                                SphGpuState<float> st, float dt) {
  const uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s < st.n) sphKickDrift(p, planes, st, s, dt);
}

}  // namespace

struct SphGpuSolver::Impl {
  SphGpuParams<float> params;
  float dt = 0.0f;
  uint32_t n = 0, cells = 0, fluid_kind = 0;
  int sort_bits = 1;
  bool elastic = false, profiling = false;
  bool masks = true;
  bool previous_passes = false;  // the separate kick-drift, memset and finish passes of the first version
  bool elastic_forces_cleared = true;  // the fused force pass clears them, the previous passes do not
  bool next_keys_ready = false;        // keys[0], order[0] hold the cell keys of the coming kick-drift
  uint64_t steps = 0;
  SphGpuPassTimes times;
  cudaStream_t stream = nullptr;
  cudaEvent_t events[7] = {};
  // Sorted arrays (double-buffered where the sort gathers them).
  DeviceArray<Vec4> pos_mass[2], velocity[2], eval_vel[2];
  DeviceArray<uint32_t> material[2], id[2];
  DeviceArray<Mat3> transform[2];
  int current = 0;
  DeviceArray<Vec4> acceleration, xsph, elastic_force;
  DeviceArray<float> pressure, pressure_term, strain;
  DeviceArray<uint32_t> keys[2], order[2], cell_start, neighbor_count, flags;
  DeviceArray<uint32_t> solid_flag, solid_offset, solid_list;  // the solid particles in sorted order
  DeviceArray<unsigned char> scan_temp;
  uint32_t num_solid = 0;
  DeviceArray<uint64_t> neighbor_masks;
  DeviceArray<unsigned char> sort_temp;
  DeviceArray<SphGpuSolidParams<float>> solids;
  DeviceArray<SphGpuPlane<float>> planes;

  SortedArrays sorted(int k) {
    return {pos_mass[k].ptr, velocity[k].ptr, eval_vel[k].ptr, material[k].ptr, id[k].ptr, transform[k].ptr};
  }
  SphGpuState<float> state() {
    SphGpuState<float> st;
    st.n = n;
    st.pos_mass = pos_mass[current].ptr;
    st.velocity = velocity[current].ptr;
    st.eval_vel = eval_vel[current].ptr;
    st.pressure = pressure.ptr;
    st.pressure_term = pressure_term.ptr;
    st.material = material[current].ptr;
    st.acceleration = acceleration.ptr;
    st.xsph = xsph.ptr;
    st.elastic_force = elastic_force.ptr;
    st.transform = transform[current].ptr;
    st.strain = strain.ptr;
    st.cell_start = cell_start.ptr;
    st.neighbor_masks = masks ? neighbor_masks.ptr : nullptr;
    st.neighbor_count = neighbor_count.ptr;
    st.error_flags = flags.ptr;
    return st;
  }
  void mark(int k) {
    if (profiling) check(cudaEventRecord(events[k], stream), "cudaEventRecord");
  }

  /// Sorts by grid cell; with `kick_drift` the kick-drift of the step is fused into the keys (made by the
  /// last force pass where it could) and the reorder.
  void sortByCell(bool kick_drift) {
    if (kick_drift && !next_keys_ready) {
      kickDriftKeysKernel<<<blocksFor(n), kBlock, 0, stream>>>(params, planes.ptr, state(), dt, keys[0].ptr,
                                                               order[0].ptr);
    } else if (!kick_drift) {
      cellKeysKernel<<<blocksFor(n), kBlock, 0, stream>>>(params, pos_mass[current].ptr, keys[0].ptr,
                                                          order[0].ptr, n);
    }
    size_t temp_bytes = sort_temp.count;
    check(cub::DeviceRadixSort::SortPairs(sort_temp.ptr, temp_bytes, keys[0].ptr, keys[1].ptr, order[0].ptr,
                                          order[1].ptr, n, 0, sort_bits, stream),
          "radix sort");
    next_keys_ready = false;
    const int other = 1 - current;
    if (kick_drift) {
      kickDriftGatherKernel<<<blocksFor(n), kBlock, 0, stream>>>(params, planes.ptr, state(), id[current].ptr,
                                                                 sorted(other), order[1].ptr, dt, solids.ptr,
                                                                 num_solid > 0 ? solid_flag.ptr : nullptr);
    } else {
      gatherKernel<<<blocksFor(n), kBlock, 0, stream>>>(sorted(current), sorted(other), order[1].ptr, n);
    }
    current = other;
    cellStartKernel<<<blocksFor(size_t(cells) + 1), kBlock, 0, stream>>>(keys[1].ptr, n, cell_start.ptr,
                                                                         cells);
    if (num_solid > 0) {
      if (!kick_drift)
        solidFlagKernel<<<blocksFor(n), kBlock, 0, stream>>>(material[current].ptr, solids.ptr,
                                                             params.max_phase, solid_flag.ptr, n);
      size_t bytes = scan_temp.count;
      check(cub::DeviceScan::ExclusiveSum(scan_temp.ptr, bytes, solid_flag.ptr, solid_offset.ptr, n, stream),
            "scan");
      solidListKernel<<<blocksFor(n), kBlock, 0, stream>>>(solid_flag.ptr, solid_offset.ptr, solid_list.ptr,
                                                           n);
    }
    check(cudaGetLastError(), "sort kernels");
  }

  /// Density, elastic forces (they read only positions and the masks), then forces with the elastic
  /// acceleration and the final kick in one pass (marks 2-4).
  void evaluateFused(bool kick) {
    const SphGpuState<float> st = state();
    if (elastic && !elastic_forces_cleared)
      check(cudaMemsetAsync(elastic_force.ptr, 0, size_t(n) * sizeof(Vec4), stream), "memset");
    elastic_forces_cleared = true;
    densityKernel<<<blocksFor(n), kBlock, 0, stream>>>(params, st);
    mark(2);
    if (elastic && num_solid > 0)
      elasticKernel<<<blocksFor(num_solid), kBlock, 0, stream>>>(params, solids.ptr, st, solid_list.ptr,
                                                                 num_solid);
    mark(3);
    forceFinishKernel<<<blocksFor(n), kBlock, 0, stream>>>(params, planes.ptr, st, dt, kick ? 1 : 0,
                                                           elastic ? 1 : 0, keys[0].ptr, order[0].ptr);
    next_keys_ready = true;
    mark(4);
    check(cudaGetLastError(), "force kernels");
  }

  void evaluate(bool kick) {
    const SphGpuState<float> st = state();
    densityKernel<<<blocksFor(n), kBlock, 0, stream>>>(params, st);
    mark(3);
    forceKernel<<<blocksFor(n), kBlock, 0, stream>>>(params, st);
    mark(4);
    if (elastic) {
      check(cudaMemsetAsync(elastic_force.ptr, 0, size_t(n) * sizeof(Vec4), stream), "memset");
      if (num_solid > 0)
        elasticKernel<<<blocksFor(num_solid), kBlock, 0, stream>>>(params, solids.ptr, st, solid_list.ptr,
                                                                   num_solid);
      elastic_forces_cleared = false;
    }
    mark(5);
    finishKernel<<<blocksFor(n), kBlock, 0, stream>>>(st, dt, kick ? 1 : 0, elastic ? 1 : 0);
    next_keys_ready = false;
    mark(6);
    check(cudaGetLastError(), "force kernels");
  }

  void checkFlags() {
    uint32_t f = 0;
    check(cudaMemcpyAsync(&f, flags.ptr, sizeof(f), cudaMemcpyDeviceToHost, stream), "flags");
    check(cudaStreamSynchronize(stream), "step");
    if (f & kSphGpuNeighborOverflow)
      throw std::runtime_error(
          "SphGpuSolver: a solid particle has more than " + std::to_string(kSphGpuMaxSolidNeighbors) +
          " neighbours of its solid (smoothing length too large for the lattice spacing)");
    if (f & kSphGpuNonFinite)
      throw std::runtime_error("SphGpuSolver: non-finite positions or velocities by step " +
                               std::to_string(steps) + " (time step too large?)");
  }
};

bool SphGpuSolver::deviceAvailable(std::string* description) {
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e != cudaSuccess || count == 0) {
    if (description) *description = e != cudaSuccess ? cudaGetErrorString(e) : "no CUDA device";
    return false;
  }
  cudaDeviceProp prop;
  if (cudaGetDeviceProperties(&prop, 0) != cudaSuccess) return false;
  if (description)
    *description = std::string(prop.name) + " (sm_" + std::to_string(prop.major) +
                   std::to_string(prop.minor) + ", " + std::to_string(prop.totalGlobalMem >> 20) + " MiB)";
  return true;
}

SphGpuSolver::SphGpuSolver(const SphGpuSystem<float>& system) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  const SphGpuParticleArrays<float>& a = system.particles;
  const size_t n = a.size();
  if (n == 0 || a.velocity.size() != n || a.material.size() != n || a.transform.size() != n)
    throw std::invalid_argument("SphGpuSolver: particle arrays are empty or differ in size (" +
                                std::to_string(n) + " positions)");
  if (system.solids.size() != size_t(system.params.max_phase) + 1 ||
      system.planes.size() != size_t(system.params.num_planes))
    throw std::invalid_argument("SphGpuSolver: solids or planes do not match the parameters");
  if (!(system.dt > 0.0f)) throw std::invalid_argument("SphGpuSolver: dt must be > 0");
  std::string device;
  if (!deviceAvailable(&device)) throw std::runtime_error("SphGpuSolver: no usable CUDA device: " + device);
  m.params = system.params;
  m.dt = system.dt;
  m.n = uint32_t(n);
  m.cells = uint32_t(size_t(m.params.dims[0]) * m.params.dims[1] * m.params.dims[2]);
  while (m.sort_bits < 32 && (uint64_t(1) << m.sort_bits) < m.cells) ++m.sort_bits;
  for (const auto& s : system.solids) m.elastic = m.elastic || s.active;
  check(cudaStreamCreate(&m.stream), "cudaStreamCreate");
  for (cudaEvent_t& e : m.events) check(cudaEventCreate(&e), "cudaEventCreate");
  std::vector<Vec4> eval(a.velocity);
  for (size_t i = 0; i < n; ++i)
    if (sphKind(a.material[i]) == kSphGpuStaticBoundary) eval[i] = {0, 0, 0, 0};
  std::vector<uint32_t> ids(n);
  for (size_t i = 0; i < n; ++i) ids[i] = uint32_t(i);
  for (size_t i = 0; i < n; ++i) {
    const uint32_t material = a.material[i], phase = sphPhase(material);
    m.fluid_kind += sphKind(material) == kSphGpuFluid;
    m.num_solid += sphKind(material) == kSphGpuFluid && phase != 0 && int(phase) <= system.params.max_phase &&
                   system.solids[phase].active;
  }
  m.solid_flag.resize(n, "solid flags");
  m.solid_offset.resize(n, "solid offsets");
  m.solid_list.resize(m.num_solid, "solid list");
  size_t scan_bytes = 0;
  check(
      cub::DeviceScan::ExclusiveSum(nullptr, scan_bytes, m.solid_flag.ptr, m.solid_offset.ptr, m.n, m.stream),
      "scan size");
  m.scan_temp.resize(scan_bytes, "scan scratch");
  m.pos_mass[0].upload(a.pos_mass, "positions");
  m.velocity[0].upload(a.velocity, "velocities");
  m.eval_vel[0].upload(eval, "velocities");
  m.material[0].upload(a.material, "materials");
  m.id[0].upload(ids, "ids");
  m.transform[0].upload(a.transform, "transforms");
  m.pos_mass[1].resize(n, "positions");
  m.velocity[1].resize(n, "velocities");
  m.eval_vel[1].resize(n, "velocities");
  m.material[1].resize(n, "materials");
  m.id[1].resize(n, "ids");
  m.transform[1].resize(n, "transforms");
  m.acceleration.resize(n, "accelerations");
  m.xsph.resize(n, "xsph");
  m.elastic_force.resize(n, "elastic forces");
  m.pressure.resize(n, "pressures");
  m.pressure_term.resize(n, "pressures");
  m.strain.resize(n, "strains");
  check(cudaMemset(m.strain.ptr, 0, n * sizeof(float)), "memset");
  check(cudaMemset(m.acceleration.ptr, 0, n * sizeof(Vec4)), "memset");
  check(cudaMemset(m.elastic_force.ptr, 0, n * sizeof(Vec4)), "memset");
  for (int k = 0; k < 2; ++k) {
    m.keys[k].resize(n, "sort keys");
    m.order[k].resize(n, "sort order");
  }
  m.cell_start.resize(size_t(m.cells) + 1, "cell starts");
  m.neighbor_count.resize(n, "neighbour counts");
  m.neighbor_masks.resize(n * size_t(9), "neighbour masks");
  m.flags.resize(1, "flags");
  check(cudaMemset(m.flags.ptr, 0, sizeof(uint32_t)), "memset");
  m.solids.upload(system.solids, "solids");
  if (!system.planes.empty()) m.planes.upload(system.planes, "planes");
  size_t temp_bytes = 0;
  check(cub::DeviceRadixSort::SortPairs(nullptr, temp_bytes, m.keys[0].ptr, m.keys[1].ptr, m.order[0].ptr,
                                        m.order[1].ptr, m.n, 0, m.sort_bits, m.stream),
        "radix sort size");
  m.sort_temp.resize(temp_bytes, "sort scratch");
  m.sortByCell(false);
  m.evaluateFused(false);
  m.checkFlags();
}

SphGpuSolver::~SphGpuSolver() {
  if (!impl_) return;
  if (impl_->stream) cudaStreamSynchronize(impl_->stream);
  for (cudaEvent_t e : impl_->events)
    if (e) cudaEventDestroy(e);
  if (impl_->stream) cudaStreamDestroy(impl_->stream);
}

void SphGpuSolver::step(int steps) {
  Impl& m = *impl_;
  for (int k = 0; k < steps; ++k) {
    m.mark(0);
    if (m.previous_passes) {
      kickDriftKernel<<<blocksFor(m.n), kBlock, 0, m.stream>>>(m.params, m.planes.ptr, m.state(), m.dt);
      m.mark(1);
      m.sortByCell(false);
      m.mark(2);
      m.evaluate(true);
    } else {
      m.sortByCell(true);
      m.mark(1);
      m.evaluateFused(true);
    }
    ++m.steps;
    if (m.profiling) {
      const int last = m.previous_passes ? 6 : 4;
      check(cudaEventSynchronize(m.events[last]), "profiling");
      float ms[6] = {};
      for (int e = 0; e < last; ++e)
        check(cudaEventElapsedTime(&ms[e], m.events[e], m.events[e + 1]), "profiling");
      if (m.previous_passes) {
        m.times.integrate += 1e-3 * (ms[0] + ms[5]);  // kick-drift, elastic acceleration + final kick
        m.times.sort += 1e-3 * ms[1];
        m.times.density += 1e-3 * ms[2];
        m.times.force += 1e-3 * ms[3];
        m.times.elastic += 1e-3 * ms[4];
      } else {  // kick-drift fused into the sort, elastic acceleration and final kick into the forces
        m.times.sort += 1e-3 * ms[0];
        m.times.density += 1e-3 * ms[1];
        m.times.elastic += 1e-3 * ms[2];
        m.times.force += 1e-3 * ms[3];
      }
      ++m.times.steps;
    }
  }
  m.checkFlags();
}

double SphGpuSolver::timedStep(int steps) {
  Impl& m = *impl_;
  cudaEvent_t begin, end;
  check(cudaEventCreate(&begin), "cudaEventCreate");
  check(cudaEventCreate(&end), "cudaEventCreate");
  check(cudaEventRecord(begin, m.stream), "cudaEventRecord");
  step(steps);  // synchronises at its end (error flags)
  check(cudaEventRecord(end, m.stream), "cudaEventRecord");
  check(cudaEventSynchronize(end), "cudaEventSynchronize");
  float ms = 0.0f;
  check(cudaEventElapsedTime(&ms, begin, end), "cudaEventElapsedTime");
  cudaEventDestroy(begin);
  cudaEventDestroy(end);
  return ms;
}

void SphGpuSolver::download(SphGpuParticleArrays<float>& out) {
  Impl& m = *impl_;
  synchronize();
  const size_t n = m.n;
  std::vector<Vec4> pos, vel, eval, acc;
  std::vector<uint32_t> material, id;
  std::vector<Mat3> transform;
  std::vector<float> pressure, strain;
  const int c = m.current;
  m.pos_mass[c].download(pos, n, "download");
  m.velocity[c].download(vel, n, "download");
  m.eval_vel[c].download(eval, n, "download");
  m.material[c].download(material, n, "download");
  m.id[c].download(id, n, "download");
  m.transform[c].download(transform, n, "download");
  m.acceleration.download(acc, n, "download");
  m.pressure.download(pressure, n, "download");
  m.strain.download(strain, n, "download");
  out.assignFromSorted(n, id.data(), pos.data(), vel.data(), material.data(), transform.data(), eval.data(),
                       pressure.data(), acc.data(), strain.data());
}

double SphGpuSolver::neighborsPerParticle() {
  Impl& m = *impl_;
  std::vector<uint32_t> counts, material;
  synchronize();
  m.neighbor_count.download(counts, m.n, "neighbour counts");
  m.material[m.current].download(material, m.n, "materials");
  uint64_t sum = 0;
  for (size_t s = 0; s < counts.size(); ++s)
    if (sphKind(material[s]) == kSphGpuFluid) sum += counts[s] & ~kSphGpuUnlisted;
  return m.fluid_kind ? double(sum) / double(m.fluid_kind) : 0.0;
}

void SphGpuSolver::setNeighborMasks(bool on) {
  impl_->masks = on;
}
void SphGpuSolver::setPreviousPasses(bool on) {
  impl_->previous_passes = on;
}
void SphGpuSolver::setProfiling(bool on) {
  impl_->profiling = on;
}
const SphGpuPassTimes& SphGpuSolver::passTimes() const {
  return impl_->times;
}
void SphGpuSolver::resetPassTimes() {
  impl_->times = SphGpuPassTimes{};
}
void SphGpuSolver::synchronize() {
  check(cudaStreamSynchronize(impl_->stream), "synchronize");
}
size_t SphGpuSolver::size() const {
  return impl_->n;
}
uint64_t SphGpuSolver::stepCount() const {
  return impl_->steps;
}

}  // namespace rc
