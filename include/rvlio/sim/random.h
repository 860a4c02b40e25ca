#pragma once
// Seeded random numbers for the simulator. The distributions are written out
// here (53-bit uniform, Box-Muller normal) instead of using <random>'s
// distributions, whose output differs between standard libraries: the same
// seed gives the same sequence everywhere.
#include <cstdint>
#include <random>

namespace rvlio::sim {

class Rng {
 public:
  explicit Rng(uint64_t seed) : engine_(seed) {}
  // A generator for an independent stream `stream` of the master seed (so
  // that, e.g., changing the LiDAR options does not change the IMU noise).
  static Rng Stream(uint64_t seed, uint64_t stream);

  double Uniform();                      // [0, 1)
  double Uniform(double lo, double hi);  // [lo, hi)
  int UniformInt(int lo, int hi);        // [lo, hi]
  double Normal();                       // N(0, 1)
  double Normal(double stddev) { return stddev * Normal(); }
  uint64_t NextU64() { return engine_(); }

 private:
  std::mt19937_64 engine_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace rvlio::sim
