#include <pcl_fot/pcl/octree/voxel_neighbors.h>

#include <algorithm>
#include <array>
#include <cstddef>

namespace pcl {
namespace fot {

VoxelNeighbors::VoxelNeighbors(const std::vector<octree::OctreeKey>& keys)
    : first_(keys.size()), last_(keys.size()) {
  const std::size_t n = keys.size();
  std::vector<std::uint32_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = std::uint32_t(i);
  const auto row = [&](std::uint32_t i) { return (std::uint64_t(keys[i].x) << 32) | keys[i].y; };
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    const std::uint64_t ra = row(a), rb = row(b);
    return ra < rb || (ra == rb && keys[a].z < keys[b].z);
  });
  // The rows in order: each one's first position in `order`, and one past the last row.
  std::vector<std::size_t> starts;
  for (std::size_t p = 0; p < n; ++p)
    if (p == 0 || row(order[p]) != row(order[p - 1])) starts.push_back(p);
  const std::size_t rows = starts.size();
  starts.push_back(n);

  // For each of the nine rows around the current one (x offset major), the first row not before it and,
  // within that row, the first voxel not below z - 1 of the voxel at hand.
  std::array<std::size_t, 9> at_row{}, at_voxel{};
  index_.reserve(9 * n);
  for (std::size_t r = 0; r < rows; ++r) {
    const std::int64_t x = keys[order[starts[r]]].x, y = keys[order[starts[r]]].y;
    for (int d = 0; d < 9; ++d) {
      const std::int64_t tx = x + d / 3 - 1, ty = y + d % 3 - 1;
      const auto before = [&](std::size_t q) {
        const octree::OctreeKey& k = keys[order[starts[q]]];
        return std::int64_t(k.x) < tx || (std::int64_t(k.x) == tx && std::int64_t(k.y) < ty);
      };
      while (at_row[d] < rows && before(at_row[d])) ++at_row[d];
      at_voxel[d] = starts[at_row[d]];
    }
    for (std::size_t p = starts[r]; p < starts[r + 1]; ++p) {
      const std::uint32_t i = order[p];
      const std::int64_t z = keys[i].z;
      first_[i] = std::uint32_t(index_.size());
      for (int d = 0; d < 9; ++d) {
        const std::size_t q = at_row[d];
        if (q == rows) continue;
        const octree::OctreeKey& k = keys[order[starts[q]]];
        if (std::int64_t(k.x) != x + d / 3 - 1 || std::int64_t(k.y) != y + d % 3 - 1) continue;
        std::size_t& v = at_voxel[d];
        while (v < starts[q + 1] && std::int64_t(keys[order[v]].z) < z - 1) ++v;
        for (std::size_t w = v; w < starts[q + 1] && std::int64_t(keys[order[w]].z) <= z + 1; ++w)
          index_.push_back(order[w]);
      }
      last_[i] = std::uint32_t(index_.size());
    }
  }
}

}  // namespace fot
}  // namespace pcl
