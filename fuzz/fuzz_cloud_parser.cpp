// Fuzz target: the tools' PCD and PLY parsers, both on every input. Each input is refused with a
// CloudFileError or gives width × height points.
#include <cstdint>
#include <cstdlib>

#include "cloud_parser.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const char* bytes = reinterpret_cast<const char*>(data);
  for (auto parse : {&fot_tools::parsePcd, &fot_tools::parsePly}) {
    try {
      const fot_tools::XyzCloud cloud = parse(bytes, size);
      if (cloud.xyz.size() != 3 * std::size_t(cloud.width) * cloud.height) std::abort();
    } catch (const fot_tools::CloudFileError&) {
    }
  }
  return 0;
}
