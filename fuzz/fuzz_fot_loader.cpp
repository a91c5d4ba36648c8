// Fuzz target: the .fot loader. Every input is refused with a FormatError or loads a valid map, which
// saves back to exactly the input's bytes.
#include <cstdint>
#include <cstdlib>
#include <string>

#include <pcl_fot/io/fot_file.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const char* bytes = reinterpret_cast<const char*>(data);
  try {
    const pcl::fot::FastOctTree tree =
        pcl::fot::io::decodeFot(bytes, size, "fuzz.fot", std::size_t(64) << 20);
    if (pcl::fot::io::encodeFot(tree) != std::string(bytes, size)) std::abort();
  } catch (const pcl::fot::io::FormatError&) {
  }
  return 0;
}
