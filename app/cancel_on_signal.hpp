// Ctrl-C and SIGTERM during long work (studies, calibrations): the flag is raised,
// the runs in flight are abandoned (they leave no row) and the command exits 130;
// running it again resumes. A second Ctrl-C kills at once.
#pragma once

#include <atomic>
#include <csignal>

namespace gapflow {

inline constexpr int kInterrupted = 130;  // 128 + SIGINT, what shells report for Ctrl-C

// Raised by SIGINT/SIGTERM; the workers' run_model calls poll it between steps.
inline std::atomic<bool> g_cancel{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" inline void on_cancel_signal(int) { g_cancel.store(true); }

// SA_RESETHAND makes a second Ctrl-C kill at once.
class CancelOnSignal {
 public:
  CancelOnSignal() {
    struct sigaction sa {};
    sa.sa_handler = on_cancel_signal;
    sa.sa_flags = SA_RESETHAND;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int_);
    sigaction(SIGTERM, &sa, &old_term_);
  }
  ~CancelOnSignal() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }

 private:
  struct sigaction old_int_ {}, old_term_ {};
};

}  // namespace gapflow
