#include <pcl_fot/io/octomap.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

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
    if (children == 0) {  // a leaf: a voxel, or a pruned cube of them
      if (!std::isfinite(log_odds)) throw fail("a leaf's log-odds is not finite");
      leaf(corner, depth, log_odds);
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
  /** A leaf's cells: a voxel, or a pruned cube of one value, kept whole. */
  void leaf(const TreeCoord& corner, unsigned depth, float log_odds) {
    const std::int32_t last = (std::int32_t(1) << (kDepth - depth)) - 1;
    const Key lo = corner.key();
    staging_.setBoxLogOdds(lo, Key{lo.x + last, lo.y + last, lo.z + last}, log_odds);
  }

  const unsigned char* at_;
  const unsigned char* end_;
  std::size_t data_bytes_;
  FastOctTree& staging_;
  const std::string& what_file_;
  std::uint64_t nodes_ = 0;
};

/** Writes a tree's nodes in OctoMap's pre-order: each node's value (its children's maximum), then its child
 * mask. */
class OtWriter {
 public:
  explicit OtWriter(const FastOctTree& tree) : tree_(tree) {}

  /** The node n, whose word is at pool offset `at` (for a word of the pool), and its subtree; returns its
   * value. */
  float node(const NodeView& n, std::size_t at) {
    const std::size_t record = put(0.0f);
    if (n.isUniform()) return patch(record, tree_.settledValue(n.uniformState()), 0);
    if (node::isValueUniform(n.word)) return patch(record, tree_.wordValue(n.word, at, 0), 0);  // as OctoMap
    float max = -std::numeric_limits<float>::infinity();
    unsigned mask = 0;
    for (unsigned o = 0; o < 8; ++o) {
      float v;
      if (n.isBitmap()) {  // a leaf word's cells, or uniform cubes: pruned leaves
        v = tree_.wordValue(n.word, at, o);
        if (std::isnan(v)) continue;
        patch(put(v), v, 0);
      } else {
        const NodeView child = n.child(tree_.words(), o);
        if (child.word == node::uniform(CellState::Unknown)) continue;
        v = node(child, n.isBitmap() ? 0 : n.childOffset(o));
      }
      mask |= 1u << o;
      max = std::max(max, v);
    }
    return patch(record, max, mask);
  }

  /** An inner node above the map's node, whose only child (octant `o`) leads towards it. */
  void chain(unsigned o) { chains_.emplace_back(put(0.0f), o); }
  /** Gives the chain nodes the value of the node they lead to. */
  void closeChains(float v) {
    for (const auto& c : chains_) patch(c.first, v, 1u << c.second);
  }

  const std::string& body() const { return body_; }
  std::uint64_t nodes() const { return nodes_; }

 private:
  std::size_t put(float v) {
    const std::size_t at = body_.size();
    body_.resize(at + 5);
    std::memcpy(&body_[at], &v, 4);
    ++nodes_;
    return at;
  }
  float patch(std::size_t record, float v, unsigned mask) {
    std::memcpy(&body_[record], &v, 4);
    body_[record + 4] = char(mask);
    return v;
  }

  const FastOctTree& tree_;
  std::string body_;
  std::uint64_t nodes_ = 0;
  std::vector<std::pair<std::size_t, unsigned>> chains_;
};

}  // namespace

std::string encodeOt(const FastOctTree& tree, std::size_t max_pool_bytes) {
  std::optional<FastOctTree> moved;
  const FastOctTree& staging = *toStaging(tree, moved, max_pool_bytes);
  OtWriter writer(staging);
  if (!staging.empty()) {
    const NodeView root = staging.contentRoot();
    // OctoMap's root is always a node of its own: above the map's node, a chain of single children.
    for (unsigned level = kDepth; level > root.level; --level) writer.chain(root.corner.octant(level));
    writer.closeChains(writer.node(root, staging.offsetOf(root)));
  }
  return headerText(kFirstLine, writer.nodes(), staging.getResolution()) + writer.body();
}

void saveOt(const FastOctTree& tree, const std::string& path, std::size_t max_pool_bytes) {
  writeFileAtomically(path, encodeOt(tree, max_pool_bytes));
}

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
