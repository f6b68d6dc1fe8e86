#pragma once
// Explicit random streams: no global RNG, never seeded from entropy. Every candidate of every wave
// owns the stream derived from (seed, wave, index), so its draws do not depend on which thread
// ran it or on what ran before it (STYLE.md, "Randomness and parallelism").
#include <cstdint>

namespace combabc {

// SplitMix64's finaliser (Steele, Lea & Flood 2014): a bijective 64-bit mixer.
constexpr std::uint64_t Mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// xoshiro256** (Blackman & Vigna 2018), keyed by a counter-style hash of (seed, stream, index).
// Written here, not taken from <random>, so that the sequence is the same on every standard
// library.
class RandomStream {
 public:
  RandomStream(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) {
    std::uint64_t h = Mix64(seed);
    h = Mix64(h ^ Mix64(stream + 0x632BE59BD9B4E019ULL));
    h = Mix64(h ^ Mix64(index + 0x8CB92BA72F3D8DD7ULL));
    for (auto& s : state_) {
      h += 0x9E3779B97F4A7C15ULL;
      s = Mix64(h);
    }
  }

  // A stream started from a raw xoshiro256** state, for checking the generator against its
  // authors' reference sequence; runs always use the keyed constructor above.
  static RandomStream FromState(std::uint64_t s0,
                                std::uint64_t s1,
                                std::uint64_t s2,
                                std::uint64_t s3) {
    RandomStream r(0, 0, 0);
    r.state_[0] = s0;
    r.state_[1] = s1;
    r.state_[2] = s2;
    r.state_[3] = s3;
    return r;
  }

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

  // Uniform on [0, 1) with 53 random bits.
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }

  // True with probability threshold / 2^53; see BernoulliThreshold().
  bool Bernoulli53(std::uint64_t threshold) { return (Next() >> 11) < threshold; }

  // Standard normal by Marsaglia's polar method (ours, so it is identical across platforms).
  double Normal();

 private:
  static constexpr std::uint64_t Rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::uint64_t state_[4];
};

// Integer threshold t with P(Bernoulli53(t)) = p to within 2^-53; p = 1 gives 2^53 (always true),
// p = 0 gives 0 (never).
std::uint64_t BernoulliThreshold(double p);

}  // namespace combabc
