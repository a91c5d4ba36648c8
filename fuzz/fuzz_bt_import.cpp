// Fuzz target: the OctoMap .bt importer. Every input is refused (FormatError, or MemoryLimitError past the
// cap) or loads a map that exports to .bt and imports back to the same cells.
#include <cstdint>
#include <cstdlib>

#include <pcl_fot/io/octomap.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  pcl::fot::io::OctoMapImportOptions options;
  options.max_pool_bytes = std::size_t(4) << 20;
  try {
    const pcl::fot::FastOctTree tree =
        pcl::fot::io::decodeBt(reinterpret_cast<const char*>(data), size, "fuzz.bt", options);
    const std::string again = pcl::fot::io::encodeBt(tree);
    if (!(pcl::fot::io::decodeBt(again.data(), again.size()) == tree)) std::abort();
  } catch (const pcl::fot::io::FormatError&) {
  } catch (const pcl::fot::MemoryLimitError&) {
  }
  return 0;
}
