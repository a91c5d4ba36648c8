#pragma once

#include <cstddef>
#include <string>

namespace pcl {
namespace fot {
namespace io {

/**
 * Writes `bytes` to a temporary file beside `path`, flushes it to disk, then renames it over `path`.
 * A crash at any moment leaves either the old file or the new one, never half of one.
 * Throws std::runtime_error with the system's reason on failure; the temporary file is removed.
 */
void writeFileAtomically(const std::string& path, const std::string& bytes);

/**
 * The whole content of a regular file. Throws std::runtime_error if it cannot be read or is not a regular
 * file (a directory, device or pipe), and std::length_error, before reading, if it is larger than max_bytes.
 */
std::string readFile(const std::string& path, std::size_t max_bytes);

}  // namespace io
}  // namespace fot
}  // namespace pcl
