// Random streams. No rand(), no std::random_device: every number comes from a
// seed that is written in the run record.
//
//  * run_seed = mix(scenario hash, base seed, replicate): identifies one job.
//  * particle streams are keyed by (base seed, replicate, purpose, particle index)
//    but NOT by the scenario hash, so that changing a parameter (gap, obstruction
//    position, friction) keeps the same particles: common random numbers for
//    sweeps and calibration.
#pragma once

#include <cmath>
#include <cstdint>

namespace gapflow {

// SplitMix64 (Steele, Lea & Flood 2014): a 64-bit bijective mixer and generator.
inline std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

inline std::uint64_t mix_seed(std::uint64_t a, std::uint64_t b) {
  std::uint64_t s = a ^ (b * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull);
  splitmix64(s);
  return splitmix64(s);
}

inline std::uint64_t run_seed(std::uint64_t scenario_hash, std::uint64_t base_seed, int replicate) {
  return mix_seed(mix_seed(scenario_hash, base_seed), static_cast<std::uint64_t>(replicate));
}

enum class StreamPurpose : std::uint64_t { size = 1, placement = 2, engine = 3, perturbation = 4 };

// A small deterministic generator for one purpose (and one particle).
class RandomStream {
 public:
  explicit RandomStream(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next_u64() { return splitmix64(state_); }
  // Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(next_u64() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Standard normal (Box-Muller; deterministic, no cached second value).
  double normal() {
    double u1 = uniform();
    double u2 = uniform();
    if (u1 < 1e-300) u1 = 1e-300;
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }

 private:
  std::uint64_t state_;
};

inline RandomStream particle_stream(std::uint64_t base_seed, int replicate, StreamPurpose purpose,
                                    std::uint64_t index) {
  std::uint64_t s = mix_seed(base_seed, static_cast<std::uint64_t>(replicate));
  s = mix_seed(s, static_cast<std::uint64_t>(purpose));
  return RandomStream(mix_seed(s, index));
}

inline RandomStream run_stream(std::uint64_t run_seed_value, StreamPurpose purpose) {
  return RandomStream(mix_seed(run_seed_value, static_cast<std::uint64_t>(purpose)));
}

}  // namespace gapflow
