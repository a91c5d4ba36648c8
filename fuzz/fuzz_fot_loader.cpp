// Fuzz target: the .fot loader. Every input is refused with a FormatError (or MemoryLimitError: a version-1
// file moved into today's nodes past the cap) or loads a valid map, which saves back to exactly the input's
// bytes, or for versions 1 and 2 to a file that loads the same map.
#include <cstdint>
#include <cstdlib>
#include <string>

#include <pcl_fot/io/fot_file.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const char* bytes = reinterpret_cast<const char*>(data);
  try {
    const pcl::fot::FastOctTree tree =
        pcl::fot::io::decodeFot(bytes, size, "fuzz.fot", std::size_t(64) << 20);
    const std::string again = pcl::fot::io::encodeFot(tree);
    if (bytes[8] != 3) {
      if (!(pcl::fot::io::decodeFot(again.data(), again.size()) == tree)) std::abort();
    } else if (again != std::string(bytes, size)) {
      std::abort();
    }
  } catch (const pcl::fot::io::FormatError&) {
  } catch (const pcl::fot::MemoryLimitError&) {
  }
  return 0;
}
