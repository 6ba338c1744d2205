#pragma once
// Deterministic random numbers for the simulator. The standard library's distributions are
// implementation-defined (libstdc++ and libc++ draw different normals from the same engine), so
// the simulator uses its own: SplitMix64 for seeding and stream splitting, xoshiro256** as the
// generator (Blackman & Vigna 2018), Box-Muller for normals. Same seed -> same numbers on every
// platform with IEEE-754 doubles and a correctly rounded sqrt (log/cos may differ by an ulp
// between libms, which the simulator's outputs are not sensitive to beyond the last bit).

#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>

namespace lasercell::datasets {

/// SplitMix64 step (Steele, Lea & Flood 2014): a well-mixed 64-bit hash of a counter.
inline std::uint64_t SplitMix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

/// Hash of a seed and a stream id, used to give every capture/profile its own stream so results
/// do not depend on the order (or the threads) in which they are rendered.
inline std::uint64_t StreamSeed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t s = seed ^ (0xD1B54A32D192ED03ull * (stream + 1));
  SplitMix64(s);
  return SplitMix64(s);
}

/// xoshiro256** generator with uniform and normal draws.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) {
    std::uint64_t s = seed;
    for (auto& v : state_) v = SplitMix64(s);
  }

  /// Next raw 64-bit value.
  std::uint64_t Next() {
    const std::uint64_t result = Rotl(state_[1] * 5, 7) * 9;
    const std::uint64_t t = state_[1] << 17;
    state_[2] ^= state_[0];
    state_[3] ^= state_[1];
    state_[1] ^= state_[2];
    state_[0] ^= state_[3];
    state_[2] ^= t;
    state_[3] = Rotl(state_[3], 45);
    return result;
  }

  /// Uniform in [0, 1) with 53 random bits.
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
  /// Uniform in [lo, hi).
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  /// Standard normal (Box-Muller; one draw per call, the second value is kept for the next).
  double Normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u1 = Uniform();
    while (u1 <= 0.0) u1 = Uniform();
    const double u2 = Uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    const double a = 2.0 * std::numbers::pi * u2;
    spare_ = r * std::sin(a);
    has_spare_ = true;
    return r * std::cos(a);
  }
  /// Normal with mean and sigma.
  double Normal(double mean, double sigma) { return mean + sigma * Normal(); }

 private:
  static std::uint64_t Rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::array<std::uint64_t, 4> state_{};
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace lasercell::datasets
