// The 1 kHz haptic force loop (thesis 5.4.2) under load: the force-loop work of the haptic_driver node
// (stroke replay sample, velocity estimate, force law (5.6), (5.7) over every handle point of the round brush
// in contact, 1/60 s low-pass) in FixedRateLoop, the node's timing code, while busy threads keep every core
// loaded. Prints period / jitter percentiles and missed ticks over the whole run. Usage: bench_haptic_loop
// [SECONDS=10] [BUSY_THREADS=cores] [REALTIME_PRIORITY=0]
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include "relaxed_connectivity/paint/brush_skeleton.h"
#include "relaxed_connectivity/paint/fixed_rate_loop.h"
#include "relaxed_connectivity/paint/haptic_force_law.h"
#include "relaxed_connectivity/paint/stroke_file.h"

using namespace rc;

namespace {

// Busy work that keeps a core at 100%: a dependent chain of floating-point operations.
void busy(const std::atomic<bool>& stop, std::atomic<double>& sink) {
  double x = 1.0;
  while (!stop.load(std::memory_order_relaxed)) {
    for (int i = 0; i < 100000; ++i) x = std::sqrt(x * 1.0000001 + 1e-9);
    sink.store(x, std::memory_order_relaxed);
  }
}

std::vector<StrokeSample> pressingStroke() {  // 1 s back and forth 2 mm into the plane z = 0
  std::vector<StrokeSample> samples;
  for (int k = 0; k <= 1000; ++k) {
    StrokeSample s;
    s.t = k * 1e-3;
    s.position = Vec3(0.02 * std::sin(2 * M_PI * s.t), 0, -0.002);
    samples.push_back(s);
  }
  return samples;
}

/// CPU time the hypervisor gave to other guests while this VM's CPUs wanted to run ("steal", the 8th value of
/// /proc/stat's cpu line) [s], summed over CPUs; negative if unknown.
double stealSeconds() {
  std::ifstream stat("/proc/stat");
  std::string line, cpu;
  if (!std::getline(stat, line)) return -1;
  std::istringstream in(line);
  in >> cpu;
  double value = 0, steal = -1;
  for (int field = 1; field <= 8 && in >> value; ++field)
    if (field == 8) steal = value;
  return steal < 0 ? -1 : steal / double(sysconf(_SC_CLK_TCK));
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 10.0;
  const double steal_start = stealSeconds();
  const int busy_threads = argc > 2 ? std::atoi(argv[2]) : int(std::thread::hardware_concurrency());
  const int priority = argc > 3 ? std::atoi(argv[3]) : 0;

  const BrushSkeleton skeleton{BrushPreset{}};
  HapticForceLaw law(skeleton.handleOffsets(), HapticForceLawOptions{});
  ContactParameters contact;  // every handle point 2 mm deep in the plane z = 0
  contact.penalty_stiffness = 400;
  contact.friction = 2;
  for (int i = 0; i < skeleton.handleCount(); ++i) {
    HandleContactState h;
    h.index = i;
    h.depth = 0.002;
    h.position = skeleton.handleOffsets()[size_t(i)] + Vec3(0, 0, -0.002);
    contact.handles.push_back(h);
  }
  const StrokeSampler stroke(pressingStroke());
  DeviceVelocityEstimator velocity;
  ForceLowPass low_pass;
  double force_sum = 0;  // keeps the work observable

  std::atomic<bool> stop{false};
  std::atomic<double> sink{0};
  std::vector<std::thread> load;
  for (int i = 0; i < busy_threads; ++i) load.emplace_back(busy, std::cref(stop), std::ref(sink));

  FixedRateLoopOptions options;
  options.rate = 1000;
  options.stats_window = int(seconds * options.rate) + 10;  // one window: the whole run
  options.realtime_priority = priority;
  FixedRateLoop loop(options);
  const uint64_t ticks = uint64_t(std::llround(seconds * options.rate));
  double work_max = 0;
  loop.start([&](uint64_t k, double t) {
    const auto begin = std::chrono::steady_clock::now();
    law.setContact(contact, t);  // a fresh contact every tick: the copy is part of the work
    const StrokeSample s = stroke.at(std::fmod(t, 1.0));
    const DeviceState device = velocity.update(t, s.position, s.orientation);
    low_pass.add(t, law.evaluate(device, t).wrench);
    force_sum += low_pass.value(t)[2];
    work_max =
        std::max(work_max, std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count());
    return k + 1 < ticks;
  });
  while (loop.running()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  loop.stop();
  stop = true;
  for (std::thread& t : load) t.join();

  const LoopTimingSummary s = loop.summary(false);
  std::printf("haptic loop: %.0f s at %.0f Hz, %d busy threads on %u cores%s%s\n", seconds, options.rate,
              busy_threads, std::thread::hardware_concurrency(), priority > 0 ? ", " : "",
              loop.schedulingNote().c_str());
  std::printf(
      "| ticks | missed | period p50 [ms] | p99 | max | jitter p50 [ms] | p99 | max | work max [us] |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  std::printf("| %llu | %llu | %.4f | %.4f | %.4f | %.4f | %.4f | %.4f | %.1f |\n",
              (unsigned long long)s.ticks, (unsigned long long)s.missed_ticks, 1e3 * s.period_p50,
              1e3 * s.period_p99, 1e3 * s.period_max, 1e3 * s.jitter_p50, 1e3 * s.jitter_p99,
              1e3 * s.jitter_max, 1e6 * work_max);
  std::printf("(mean filtered force %.3f N, sink %.3f)\n", force_sum / double(s.ticks), sink.load());
  const double steal_end = stealSeconds();
  if (steal_start >= 0 && steal_end >= 0)
    std::printf("steal time during the run (the hypervisor ran other guests): %.0f ms over all CPUs\n",
                1e3 * (steal_end - steal_start));
  return 0;
}
