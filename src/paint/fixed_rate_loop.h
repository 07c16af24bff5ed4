// A loop on its own thread that calls a tick function at a fixed rate with absolute deadlines on the
// monotonic clock (clock_nanosleep TIMER_ABSTIME: no drift, a late tick does not shift the schedule) and
// measures itself (LoopTimingStats). The haptic force loop of thesis 5.4.2 runs in it, in the node and in the
// bench alike.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

#include "relaxed_connectivity/paint/loop_timing_stats.h"

namespace rc {

struct FixedRateLoopOptions {
  double rate = 1000;         ///< ticks per second
  bool paced = true;          ///< false: no sleeping, loop time = tick / rate (as fast as possible)
  int stats_window = 1000;    ///< ticks in the timing window (1 s at 1 kHz)
  int realtime_priority = 0;  ///< > 0: try SCHED_FIFO at this priority (needs CAP_SYS_NICE; else a note)
};

class FixedRateLoop {
 public:
  /// Called once per tick with the tick index and the loop time t [s] since start(); returns false to stop.
  using Tick = std::function<bool(uint64_t tick, double t)>;

  explicit FixedRateLoop(FixedRateLoopOptions options);
  ~FixedRateLoop();  ///< stops the thread
  FixedRateLoop(const FixedRateLoop&) = delete;
  FixedRateLoop& operator=(const FixedRateLoop&) = delete;

  void start(Tick tick);
  /// Asks the thread to stop and joins it.
  void stop();
  bool running() const { return running_; }
  /// Timing over the window so far; `clear_window` starts the next window.
  LoopTimingSummary summary(bool clear_window);
  /// Outcome of the realtime_priority request ("" when none was made).
  std::string schedulingNote() const;
  const FixedRateLoopOptions& options() const { return options_; }

 private:
  void run(Tick tick);

  FixedRateLoopOptions options_;
  std::thread thread_;
  std::atomic<bool> stop_requested_{false}, running_{false};
  mutable std::mutex mutex_;  // guards stats_ and scheduling_note_
  LoopTimingStats stats_;
  std::string scheduling_note_;
};

}  // namespace rc
