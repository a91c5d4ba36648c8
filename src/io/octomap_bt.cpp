#include <pcl_fot/io/octomap.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include <pcl_fot/io/file_io.h>

#include "io/octomap_format.h"
#include "io/region_copy.h"

namespace pcl {
namespace fot {
namespace io {
namespace {

using namespace octomap_format;

constexpr char kFirstLine[] = "# Octomap OcTree binary file";

/** A child's two bits in a .bt record: 01 free leaf (bit 2i), 10 occupied leaf (bit 2i+1), 11 inner. */
unsigned childCode(NodeWord w) {
  if (!node::isUniform(w)) return 3;
  switch (node::uniformState(w)) {
    case CellState::Free:
      return 1;
    case CellState::Occupied:
      return 2;
    default:
      return 0;
  }
}

/** Writes the staging tree's nodes in OctoMap's pre-order. */
class BtWriter {
 public:
  explicit BtWriter(const FastOctTree& staging) : words_(staging.words()) {}

  /** A word of the tree at `level` and its subtree. */
  void node(NodeWord w, unsigned level) {
    NodeWord children[8];
    for (unsigned o = 0; o < 8; ++o) children[o] = NodeView::childWord(words_, w, o);
    std::uint32_t codes = 0;
    for (unsigned o = 0; o < 8; ++o) codes |= childCode(children[o]) << (2 * o);
    record(codes);
    for (unsigned o = 0; o < 8; ++o)
      if (childCode(children[o]) == 3) node(children[o], level - 1);
  }

  /** An inner node above the map's node, whose only child (octant `o`) leads towards it. */
  void chain(unsigned o) { record(3u << (2 * o)); }
  /** The inner node whose only child, octant `o`, is the uniform word w: a pruned leaf. */
  void leaf(unsigned o, NodeWord w) { record(childCode(w) << (2 * o)); }

  const std::string& body() const { return body_; }
  std::uint64_t nodes() const { return nodes_; }

 private:
  void record(std::uint32_t codes) {
    body_.push_back(char(codes & 0xFFu));
    body_.push_back(char((codes >> 8) & 0xFFu));
    for (unsigned o = 0; o < 8; ++o) nodes_ += ((codes >> (2 * o)) & 3u) != 0;
  }

  const NodeWord* words_;
  std::string body_;
  std::uint64_t nodes_ = 1;  // the root
};

/** Reads OctoMap's pre-order records into the staging tree. */
class BtReader {
 public:
  BtReader(const unsigned char* body, std::size_t size, FastOctTree& staging, const std::string& name)
      : at_(body), end_(body + size), staging_(staging), name_(name) {}

  void node(unsigned depth, const TreeCoord& corner) {
    if (end_ - at_ < 2) throw fail("the tree ends early: the file is truncated");
    const std::uint32_t codes = std::uint32_t(at_[0]) | std::uint32_t(at_[1]) << 8;
    at_ += 2;
    const unsigned child_level = kDepth - depth - 1;
    const std::int32_t half = std::int32_t(1) << child_level;
    for (unsigned o = 0; o < 8; ++o) {
      const unsigned code = (codes >> (2 * o)) & 3u;
      if (code == 0) continue;
      ++nodes_;
      const TreeCoord child = corner.child(o, child_level);
      if (code == 3) {
        if (depth + 1 == kDepth) throw fail("a voxel at the deepest level has children");
        node(depth + 1, child);
        continue;
      }
      const Key lo = child.key();
      const Key hi{lo.x + half - 1, lo.y + half - 1, lo.z + half - 1};
      staging_.setBox(lo, hi, code == 1 ? CellState::Free : CellState::Occupied);
    }
  }

  std::size_t left() const { return std::size_t(end_ - at_); }
  std::uint64_t nodes() const { return nodes_; }
  FormatError fail(const std::string& what) const {
    return FormatError("pcl::fot::io: '" + name_ + "' is not a valid OctoMap .bt file: " + what);
  }

 private:
  const unsigned char* at_;
  const unsigned char* end_;
  FastOctTree& staging_;
  const std::string& name_;
  std::uint64_t nodes_ = 1;  // the root
};

}  // namespace

std::string encodeBt(const FastOctTree& map, std::size_t max_pool_bytes) {
  // OctoMap's writeBinary writes the maximum-likelihood map, pruned.
  std::optional<FastOctTree> settled;
  if (map.getValueLeafCount() > 0) {
    settled.emplace(map);
    settled->toMaxLikelihood();
  }
  std::optional<FastOctTree> moved;
  const FastOctTree& staging = *toStaging(settled ? *settled : map, moved, max_pool_bytes);
  const double res = staging.getResolution();

  BtWriter writer(staging);
  if (!staging.empty()) {
    // Every cell lies in OctoMap's root cube, so the node holding them all does too; the levels above it are
    // chains of single children.
    const NodeView root = staging.contentRoot();
    // A uniform node is a pruned leaf of its parent, as OctoMap writes it; OctoMap's root is always a record.
    const bool pruned = root.isUniform() && root.level < kDepth;
    const unsigned holder = pruned ? root.level + 1 : root.level;
    for (unsigned level = kDepth; level > holder; --level) writer.chain(root.corner.octant(level));
    if (pruned)
      writer.leaf(root.corner.octant(holder), root.word);
    else
      writer.node(root.word, root.level);
  }
  return headerText(kFirstLine, staging.empty() ? 0 : writer.nodes(), res) + writer.body();
}

void saveBt(const FastOctTree& tree, const std::string& path, std::size_t max_pool_bytes) {
  writeFileAtomically(path, encodeBt(tree, max_pool_bytes));
}

FastOctTree decodeBt(const char* bytes, std::size_t size, const std::string& name,
                     const OctoMapImportOptions& options) {
  const std::string what_file = "pcl::fot::io: '" + name + "' is not a valid OctoMap .bt file";
  auto fail = [&](const std::string& what) { return FormatError(what_file + ": " + what); };
  // Every occupancy tree type (OcTree, ColorOcTree, OcTreeStamped, ...) writes the same .bt body, and
  // OctoMap reads any of them as an OcTree: so do we.
  const Header h = readHeader(bytes, size, kFirstLine, what_file);
  const std::size_t body = size - h.body;
  // Each inner node takes 2 bytes and has at most 8 children.
  if (h.size > 1 + 4 * std::uint64_t(body))
    throw fail("the size " + std::to_string(h.size) + " cannot fit the file");
  return readBody(bytes, size, h, options, what_file,
                  [&](const unsigned char* at, std::size_t n, FastOctTree& staging) {
                    return BtReader(at, n, staging, name);
                  });
}

FastOctTree loadBt(const std::string& path, const OctoMapImportOptions& options) {
  std::string bytes;
  try {  // a .bt body is at least 2 bytes per 8 nodes, and the map grows no larger than the cap
    bytes = readFile(path, std::size_t(1) << 34);
  } catch (const std::length_error& e) {
    throw FormatError(e.what());
  }
  return decodeBt(bytes.data(), bytes.size(), path, options);
}

}  // namespace io
}  // namespace fot
}  // namespace pcl
