#include "vesph/io/progress.hpp"

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>

namespace vesph {
namespace {
volatile std::sig_atomic_t g_interrupt = 0;

extern "C" void onSignal(int sig) {
  g_interrupt = 1;
  std::signal(sig, SIG_DFL);  // a second signal ends the process immediately
}

std::string formatSeconds(double s) {
  char buf[32];
  if (!std::isfinite(s) || s < 0) return "?";
  if (s < 60) std::snprintf(buf, sizeof buf, "%.0f s", s);
  else if (s < 3600) std::snprintf(buf, sizeof buf, "%.0f min %02.0f s", std::floor(s / 60), std::fmod(s, 60));
  else std::snprintf(buf, sizeof buf, "%.0f h %02.0f min", std::floor(s / 3600), std::fmod(s / 60, 60));
  return buf;
}
}  // namespace

void installInterruptHandlers() {
  g_interrupt = 0;
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
}
bool interruptRequested() { return g_interrupt != 0; }
void resetInterrupt() { g_interrupt = 0; }

bool Progress::stderrIsTerminal() { return isatty(STDERR_FILENO) == 1; }

Progress::Progress(double t0, double t_end, bool quiet)
    : t0_(t0), t_end_(t_end), live_(!quiet && stderrIsTerminal()), interval_(live_ ? 0.2 : 10.0),
      start_(Clock::now()), last_(start_) {}

void Progress::update(double t, std::uint64_t steps, double dt, bool force) {
  const auto now = Clock::now();
  const double since = std::chrono::duration<double>(now - last_).count();
  if (!force && since < interval_) return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double frac = t_end_ > t0_ ? (t - t0_) / (t_end_ - t0_) : 1.0;
  const double eta = frac > 0 ? elapsed * (1 - frac) / frac : NAN;
  std::fprintf(stderr, "%st = %.6g s / %.6g s (%5.1f %%)  step %llu  dt %.3e s  elapsed %s  ETA %s%s",
               live_ ? "\r" : "", t, t_end_, 100 * frac, static_cast<unsigned long long>(steps), dt,
               formatSeconds(elapsed).c_str(), formatSeconds(eta).c_str(), live_ ? "   " : "\n");
  std::fflush(stderr);
  printed_ = true;
}

void Progress::finish() {
  if (live_ && printed_) std::fprintf(stderr, "\n");
}

}  // namespace vesph
