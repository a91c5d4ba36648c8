#pragma once
// How the PCL adapters tell that a cached structure still matches its cloud.

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace pcl {
namespace fot {
namespace detail {

/**
 * A 64-bit FNV-1a hash, over 32-bit words, of the x, y, z of `count` points (stride in bytes) and of an index
 * list: cheap enough to tell on every call whether a cached structure still matches its cloud, even one
 * changed in place. Each step is a bijection of the hash, so any one word changed changes the result.
 */
inline std::uint64_t cloudFingerprint(const float* xyz, std::size_t count, std::size_t stride_bytes,
                                      const std::int32_t* indices = nullptr, std::size_t index_count = 0) {
  std::uint64_t h = 1469598103934665603ull;
  const auto mix = [&h](const void* word) {
    std::uint32_t w;
    std::memcpy(&w, word, sizeof w);
    h = (h ^ w) * 1099511628211ull;
  };
  const char* bytes = reinterpret_cast<const char*>(xyz);
  for (std::size_t i = 0; i < count; ++i)
    for (std::size_t a = 0; a < 3; ++a) mix(bytes + i * stride_bytes + a * sizeof(float));
  for (std::size_t i = 0; i < index_count && indices; ++i) mix(indices + i);
  return h;
}

}  // namespace detail
}  // namespace fot
}  // namespace pcl
