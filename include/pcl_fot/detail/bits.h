#pragma once
// Bit operations for the hot paths: the compiler's builtins where there are some, portable code elsewhere.

#include <cstdint>

#if defined(_MSC_VER) && !defined(__clang__)
#include <intrin.h>
#endif

namespace pcl {
namespace fot {
namespace detail {

/** Index of the lowest set bit of x, which must not be 0. */
inline unsigned lowestBit(std::uint64_t x) {
#if defined(__GNUC__) || defined(__clang__)
  return unsigned(__builtin_ctzll(x));
#elif defined(_MSC_VER)
  unsigned long i;
  _BitScanForward64(&i, x);
  return unsigned(i);
#else
  unsigned i = 0;
  while (!((x >> i) & 1u)) ++i;
  return i;
#endif
}

/** Index of the highest set bit of x, which must not be 0. */
inline unsigned highestBit(std::uint64_t x) {
#if defined(__GNUC__) || defined(__clang__)
  return 63u - unsigned(__builtin_clzll(x));
#elif defined(_MSC_VER)
  unsigned long i;
  _BitScanReverse64(&i, x);
  return unsigned(i);
#else
  unsigned i = 63;
  while (!((x >> i) & 1u)) --i;
  return i;
#endif
}

/** Set bits of x, in registers: without -mpopcnt the builtin is a library call. */
constexpr unsigned popcount64(std::uint64_t x) {
  x = x - ((x >> 1) & 0x5555555555555555ull);
  x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
  x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0Full;
  return unsigned((x * 0x0101010101010101ull) >> 56);
}

}  // namespace detail
}  // namespace fot
}  // namespace pcl
