#include "relaxed_connectivity/paint/fixed_rate_loop.h"

#include <pthread.h>
#include <sched.h>
#include <time.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace rc {
namespace {

int64_t monotonicNs() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

void sleepUntilNs(int64_t deadline) {
  timespec ts;
  ts.tv_sec = time_t(deadline / 1000000000);
  ts.tv_nsec = long(deadline % 1000000000);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace

FixedRateLoop::FixedRateLoop(FixedRateLoopOptions options)
    : options_(options), stats_(1.0 / options.rate, options.stats_window) {
  if (!(options.rate > 0) || !std::isfinite(options.rate))
    throw std::invalid_argument("loop rate must be > 0 (got " + std::to_string(options.rate) + ")");
}

FixedRateLoop::~FixedRateLoop() {
  stop();
}

void FixedRateLoop::start(Tick tick) {
  if (thread_.joinable()) throw std::logic_error("FixedRateLoop started twice");
  stop_requested_ = false;
  running_ = true;
  thread_ = std::thread([this, tick = std::move(tick)] { run(tick); });
}

void FixedRateLoop::stop() {
  stop_requested_ = true;
  if (thread_.joinable()) thread_.join();
  running_ = false;
}

LoopTimingSummary FixedRateLoop::summary(bool clear_window) {
  std::lock_guard<std::mutex> lock(mutex_);
  LoopTimingSummary s = stats_.summary();
  if (clear_window) stats_.clearWindow();
  return s;
}

std::string FixedRateLoop::schedulingNote() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return scheduling_note_;
}

void FixedRateLoop::run(Tick tick) {
  if (options_.realtime_priority > 0) {
    sched_param param{};
    param.sched_priority = options_.realtime_priority;
    const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
    std::lock_guard<std::mutex> lock(mutex_);
    scheduling_note_ =
        err == 0 ? "SCHED_FIFO priority " + std::to_string(options_.realtime_priority)
                 : std::string("SCHED_FIFO refused (") + std::strerror(err) + "): running at normal priority";
  }
  const int64_t period_ns = std::llround(1e9 / options_.rate);
  const int64_t start_ns = monotonicNs();
  int64_t scheduled_ns = start_ns;
  for (uint64_t k = 0; !stop_requested_; ++k) {
    double t;
    if (options_.paced) {
      sleepUntilNs(scheduled_ns);
      const int64_t started_ns = monotonicNs();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        stats_.record(1e-9 * double(scheduled_ns - start_ns), 1e-9 * double(started_ns - start_ns));
      }
      t = 1e-9 * double(started_ns - start_ns);
    } else {
      t = double(k) / options_.rate;
    }
    if (!tick(k, t)) break;
    if (options_.paced) {
      scheduled_ns += period_ns;
      // Far behind (more than a period past the next slot): resume at the next slot from now, no burst.
      const int64_t now_ns = monotonicNs();
      if (now_ns - scheduled_ns > period_ns) {
        const int64_t skipped = (now_ns - scheduled_ns) / period_ns;
        scheduled_ns += skipped * period_ns;
        std::lock_guard<std::mutex> lock(mutex_);
        stats_.recordSkipped(uint64_t(skipped));
      }
    }
  }
  running_ = false;
}

}  // namespace rc
