// Fuzz target: the OctoMap .ot importer, with the checks of octomap_import_checks.h.
#include "octomap_import_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return checkOctoMapImport(data, size, [](const char* bytes, std::size_t n, const auto& options) {
    return pcl::fot::io::decodeOt(bytes, n, "fuzz.ot", options);
  });
}
