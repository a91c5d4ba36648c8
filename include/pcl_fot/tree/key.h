#pragma once

#include <cstdint>
#include <functional>
#include <string>

namespace pcl {
namespace fot {

/** The three states a cell can hold. The paper's binary map is the special case without Free. */
enum class CellState : std::uint8_t { Unknown = 0, Free = 1, Occupied = 2 };

/** Signed integer voxel coordinates relative to the map origin. */
struct Key {
  std::int32_t x = 0;
  std::int32_t y = 0;
  std::int32_t z = 0;

  friend bool operator==(const Key& a, const Key& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
  friend bool operator!=(const Key& a, const Key& b) { return !(a == b); }
};

/** Keys must lie in [kMinKey, kMaxKey] on every axis; that is ±2^29 cells. */
constexpr std::int32_t kMinKey = -(1 << 29);
constexpr std::int32_t kMaxKey = (1 << 29) - 1;

/** Deepest possible root level: a level-l node spans 2^l cells per axis. */
constexpr unsigned kMaxLevel = 31;

inline bool isValidKey(const Key& k) {
  return k.x >= kMinKey && k.x <= kMaxKey && k.y >= kMinKey && k.y <= kMaxKey && k.z >= kMinKey &&
         k.z <= kMaxKey;
}

inline std::string toString(const Key& k) {
  return "(" + std::to_string(k.x) + ", " + std::to_string(k.y) + ", " + std::to_string(k.z) + ")";
}

struct KeyHash {
  std::size_t operator()(const Key& k) const {
    const std::uint64_t h = (std::uint64_t(std::uint32_t(k.x)) * 0x9E3779B97F4A7C15ull) ^
                            (std::uint64_t(std::uint32_t(k.y)) * 0xC2B2AE3D27D4EB4Full) ^
                            (std::uint64_t(std::uint32_t(k.z)) * 0x165667B19E3779F9ull);
    return std::size_t(h ^ (h >> 29));
  }
};

}  // namespace fot
}  // namespace pcl
