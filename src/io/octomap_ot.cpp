#include <pcl_fot/io/octomap.h>

#include <cmath>
#include <cstring>

#include <pcl_fot/io/file_io.h>

#include "io/octomap_format.h"

namespace pcl {
namespace fot {
namespace io {
namespace {

using namespace octomap_format;

constexpr char kFirstLine[] = "# Octomap OcTree file";

/** Bytes each node's data takes before its child mask: the log-odds float, plus ColorOcTree's colour. */
std::size_t dataBytes(const std::string& id) {
  if (id == "OcTree" || id == "OcTreeStamped") return 4;  // OcTreeStamped does not write its time stamps
  if (id == "ColorOcTree") return 4 + 3;
  return 0;
}

/** Reads OctoMap's pre-order nodes (data, then a byte with a bit per existing child) into the staging tree.
 */
class OtReader {
 public:
  OtReader(const unsigned char* body, std::size_t size, std::size_t data_bytes, FastOctTree& staging,
           const std::string& what_file)
      : at_(body), end_(body + size), data_bytes_(data_bytes), staging_(staging), what_file_(what_file) {}

  void node(unsigned depth, const TreeCoord& corner) {
    if (std::size_t(end_ - at_) < data_bytes_ + 1) throw fail("the tree ends early: the file is truncated");
    float log_odds;
    std::memcpy(&log_odds, at_, sizeof log_odds);
    const unsigned children = at_[data_bytes_];
    at_ += data_bytes_ + 1;
    ++nodes_;
    const std::int32_t side = std::int32_t(1) << (kDepth - depth);
    if (children == 0) {  // a leaf: a voxel, or a pruned cube of them
      if (std::isnan(log_odds)) throw fail("a leaf's log-odds is not a number");
      const Key lo = corner.key();
      staging_.setBox(lo, Key{lo.x + side - 1, lo.y + side - 1, lo.z + side - 1},
                      log_odds >= 0.0f ? CellState::Occupied : CellState::Free);
      return;
    }
    if (depth == kDepth) throw fail("a voxel at the deepest level has children");
    for (unsigned o = 0; o < 8; ++o)
      if ((children >> o) & 1u) node(depth + 1, corner.child(o, kDepth - depth - 1));
  }

  std::size_t left() const { return std::size_t(end_ - at_); }
  std::uint64_t nodes() const { return nodes_; }
  FormatError fail(const std::string& what) const { return FormatError(what_file_ + ": " + what); }

 private:
  const unsigned char* at_;
  const unsigned char* end_;
  std::size_t data_bytes_;
  FastOctTree& staging_;
  const std::string& what_file_;
  std::uint64_t nodes_ = 0;
};

}  // namespace

FastOctTree decodeOt(const char* bytes, std::size_t size, const std::string& name,
                     const OctoMapImportOptions& options) {
  const std::string what_file = "pcl::fot::io: '" + name + "' is not a valid OctoMap .ot file";
  auto fail = [&](const std::string& what) { return FormatError(what_file + ": " + what); };
  const Header h = readHeader(bytes, size, kFirstLine, what_file);
  const std::size_t data_bytes = dataBytes(h.id);
  if (data_bytes == 0)
    throw fail("the tree type is '" + h.id + "'; this reader knows OcTree, OcTreeStamped and ColorOcTree");
  const std::size_t body = size - h.body;
  if (h.size > body / (data_bytes + 1))
    throw fail("its header's size, " + std::to_string(h.size) +
               " nodes, takes more bytes than the file holds: it is truncated, or the size is wrong");
  return readBody(bytes, size, h, options, what_file,
                  [&](const unsigned char* at, std::size_t n, FastOctTree& staging) {
                    return OtReader(at, n, data_bytes, staging, what_file);
                  });
}

FastOctTree loadOt(const std::string& path, const OctoMapImportOptions& options) {
  std::string bytes;
  try {  // 5 bytes or more per node, and the map grows no larger than the cap
    bytes = readFile(path, std::size_t(1) << 34);
  } catch (const std::length_error& e) {
    throw FormatError(e.what());
  }
  return decodeOt(bytes.data(), bytes.size(), path, options);
}

}  // namespace io
}  // namespace fot
}  // namespace pcl
