#pragma once
// Progress of a run on stderr: a live line on a terminal (simulated time, steps, step size,
// ETA); with --quiet or when stderr is not a terminal, a plain line every `interval` seconds.
#include <chrono>
#include <string>

namespace vesph {

class Progress {
 public:
  Progress(double t0, double t_end, bool quiet);
  void update(double t, std::uint64_t steps, double dt, bool force = false);
  void finish();
  static bool stderrIsTerminal();

 private:
  using Clock = std::chrono::steady_clock;
  double t0_, t_end_;
  bool live_;
  double interval_;
  Clock::time_point start_, last_;
  bool printed_ = false;
};

// SIGINT/SIGTERM handling: the first signal requests a clean stop (the run writes its state
// and exits 130); a second one terminates at once.
void installInterruptHandlers();
bool interruptRequested();
void resetInterrupt();

}  // namespace vesph
