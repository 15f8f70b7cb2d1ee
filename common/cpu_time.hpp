// CPU time, as the kernel counts it: what a run or a calibration cost, apart from the wall
// time that swells when other work shares the cores.
#pragma once

#include <ctime>

namespace gapflow {

// CPU seconds of the calling thread (what Google Benchmark's CPU column counts).
inline double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// CPU seconds of the whole process, every thread (user + system).
inline double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace gapflow
