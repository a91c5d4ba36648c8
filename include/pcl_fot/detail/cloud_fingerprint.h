#pragma once
// How the PCL adapters tell that a cached structure still matches its cloud.

#include <cstddef>
#include <cstdint>

namespace pcl {
namespace fot {
namespace detail {

/**
 * A 64-bit FNV-1a hash of the x, y, z of `count` points (stride in bytes) and of an index list: cheap
 * enough to tell on every call whether a cached structure still matches its cloud, even one changed in place.
 */
inline std::uint64_t cloudFingerprint(const float* xyz, std::size_t count, std::size_t stride_bytes,
                                      const std::int32_t* indices = nullptr, std::size_t index_count = 0) {
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&h](const void* data, std::size_t n) {
    const unsigned char* b = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  };
  const char* bytes = reinterpret_cast<const char*>(xyz);
  for (std::size_t i = 0; i < count; ++i) mix(bytes + i * stride_bytes, 3 * sizeof(float));
  if (indices) mix(indices, index_count * sizeof(std::int32_t));
  return h;
}

}  // namespace detail
}  // namespace fot
}  // namespace pcl
