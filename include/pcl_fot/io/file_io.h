#pragma once

#include <cstddef>
#include <string>

namespace pcl {
namespace fot {
namespace io {

/**
 * Writes `bytes` to `path` so that a crash at any moment leaves either the old file or the new one, never
 * half of one: to a temporary file beside it, flushed to disk, then renamed over it. A link is followed, and
 * the file it names is replaced, not the link. A target that exists and is not a regular file (a device such
 * as /dev/null or /dev/stdout, a pipe) is written into directly, as a stream: it has no old content to keep;
 * a directory is refused.
 *
 * The temporary file is named `.<name>.pcl_fot-tmp.<pid>.<n>` beside the target. One left behind by a
 * process that was killed is removed by the next write of the same target. Throws std::runtime_error with
 * the system's reason on failure; the temporary file is removed.
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
