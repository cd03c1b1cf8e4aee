#pragma once
// A seeded random generator whose draws are the same with every standard library: the engine is
// std::mt19937_64 (its output sequence is fixed by the C++ standard), and the uniform, integer and
// Gaussian draws are written here (std::uniform_real_distribution, std::normal_distribution and
// std::shuffle are implementation-defined). Synthetic data made with it are reproducible across
// compilers for the same seed.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <random>

namespace photopose {

class PortableRandom {
 public:
  explicit PortableRandom(uint64_t seed) : engine_(seed) {}
  // An independent stream of a seed: the seed and the stream number mixed by SplitMix64
  // (Steele, Lea, Flood 2014), so that streams of nearby seeds are unrelated.
  PortableRandom(uint64_t seed, uint64_t stream) : engine_(Mix(seed ^ Mix(stream + 1))) {}

  // Uniform in [0, 1) with 53 random bits.
  double Uniform01() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  // Uniform in [lo, hi).
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform01(); }
  // Uniform integer in [0, bound) for bound >= 1, without bias (rejection of the last partial
  // range of 2^64).
  uint64_t Below(uint64_t bound) {
    const uint64_t limit = UINT64_MAX - UINT64_MAX % bound;
    uint64_t value;
    do {
      value = engine_();
    } while (value >= limit);
    return value % bound;
  }
  // Standard normal draw: Marsaglia's polar method (the second value of a pair is kept for the
  // next call).
  double Gaussian() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u, v, s;
    do {
      u = Uniform(-1.0, 1.0);
      v = Uniform(-1.0, 1.0);
      s = u * u + v * v;
    } while (s >= 1.0 || s == 0.0);
    const double factor = std::sqrt(-2.0 * std::log(s) / s);
    spare_ = v * factor;
    has_spare_ = true;
    return u * factor;
  }
  // Vectors of independent draws, their components drawn LAST TO FIRST. The order is written out
  // because the arguments of Eigen::Vector3d(Gaussian(), Gaussian(), Gaussian()) are evaluated in
  // an unspecified order (GCC: last first; Clang: first first), which made the same seed give
  // different blocks with the two compilers; last-to-first keeps the blocks GCC always made.
  Eigen::Vector2d Gaussian2() {
    const double y = Gaussian();
    return Eigen::Vector2d(Gaussian(), y);
  }
  Eigen::Vector3d Gaussian3() {
    const double z = Gaussian();
    const double y = Gaussian();
    return Eigen::Vector3d(Gaussian(), y, z);
  }
  Eigen::Vector2d Uniform01x2() {
    const double y = Uniform01();
    return Eigen::Vector2d(Uniform01(), y);
  }

 private:
  static uint64_t Mix(uint64_t x) {
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
  }

  std::mt19937_64 engine_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace photopose
