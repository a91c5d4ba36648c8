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

/** Moves bit i of v to bit 3i, for v below 2^21: one axis of a Morton code. */
constexpr std::uint64_t spreadBits3(std::uint64_t v) {
  v &= 0x1FFFFFull;
  v = (v | v << 32) & 0x1F00000000FFFFull;
  v = (v | v << 16) & 0x1F0000FF0000FFull;
  v = (v | v << 8) & 0x100F00F00F00F00Full;
  v = (v | v << 4) & 0x10C30C30C30C30C3ull;
  return (v | v << 2) & 0x1249249249249249ull;
}

/** The Morton code of a cell, each coordinate below 2^21: x's bits lowest, as the tree numbers octants. */
constexpr std::uint64_t morton3(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  return spreadBits3(x) | spreadBits3(y) << 1 | spreadBits3(z) << 2;
}

}  // namespace detail
}  // namespace fot
}  // namespace pcl
