#pragma once
// What the .bt and .ot import fuzz targets check, given the decoder of their format.

#include <cstdint>
#include <cstdlib>
#include <optional>
#include <string>

#include <pcl_fot/io/octomap.h>

/**
 * Every input is refused (FormatError, or MemoryLimitError for values past the cap) or loads a map whose
 * exported .bt imports back as its maximum-likelihood map, and whose pool follows the file's size unless it
 * carries values (a pruned .ot leaf between the clamps gives each of its cells the value); moved a cell off
 * OctoMap's grid it holds the same cells or is refused past the cap. `decode(bytes, size, options)` is the
 * importer.
 */
template <typename Decode>
int checkOctoMapImport(const std::uint8_t* data, std::size_t size, Decode&& decode) {
  // A realistic cap: at origin 0 the map is OctoMap's tree node for node, so its pool follows the file's
  // size, and a cost that follows the volume instead is a finding, as is needing the cap at all.
  // 4 MiB: a pruned .ot leaf between the clamps is still spelled out cell by cell (issue 44, item 3), so a
  // larger cap lets one leaf cost seconds, past the fuzzer's timeout under its instrumentation.
  pcl::fot::io::OctoMapImportOptions options;
  options.max_pool_bytes = std::size_t(4) << 20;
  const char* bytes = reinterpret_cast<const char*>(data);
  std::optional<pcl::fot::FastOctTree> tree;
  try {
    tree.emplace(decode(bytes, size, options));
  } catch (const pcl::fot::io::FormatError&) {
    return 0;
  } catch (const pcl::fot::MemoryLimitError&) {
    return 0;
  }
  if (tree->getValueLeafCount() == 0 && tree->getMemoryBytes() > 64 * size + 4096) std::abort();
  const std::string again = pcl::fot::io::encodeBt(*tree);
  pcl::fot::FastOctTree settled = *tree;
  settled.toMaxLikelihood();
  if (!(pcl::fot::io::decodeBt(again.data(), again.size()) == settled)) std::abort();
  // One cell off OctoMap's grid, a large cube splits along its surface: the same cells, or a refusal.
  if (size == 0 || !(data[size - 1] & 1)) return 0;
  options.origin[0] = tree->getResolution();
  options.max_pool_bytes = std::size_t(4) << 20;
  try {
    const pcl::fot::FastOctTree moved = decode(bytes, size, options);
    if (moved.getOccupiedCount() != tree->getOccupiedCount() || moved.getFreeCount() != tree->getFreeCount())
      std::abort();
  } catch (const pcl::fot::MemoryLimitError&) {
  }
  return 0;
}
