#include <pcl_fot/io/octomap_bt.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <pcl_fot/io/file_io.h>

namespace pcl {
namespace fot {
namespace io {
namespace {

constexpr unsigned kDepth = 16;  // OctoMap's tree depth: 65536 cells per axis
constexpr std::int32_t kCentre = 32768;
constexpr char kFirstLine[] = "# Octomap OcTree binary file";

// OctoMap's cells live in a staging tree whose tree coordinates are OctoMap's keys plus 0x2AAA0000, so that
// its nodes are exactly OctoMap's: the level-16 cube at kStagingBase is OctoMap's root.
constexpr std::uint32_t kStagingBase = 0x2AAA0000u;
std::int32_t stagingKey(std::int32_t octomap_key) {
  return tree_coord::toKey(kStagingBase + std::uint32_t(octomap_key));
}

/** The origin in whole cells from coordinate 0; throws if it is not on OctoMap's grid. */
std::int32_t cellsFromZero(double origin, double res, const char* axis) {
  const double cells = origin / res;
  const double whole = std::round(cells);
  if (!(std::abs(cells - whole) <= 1e-6) || std::abs(whole) > double(kMaxKey))
    throw std::invalid_argument(
        std::string("pcl::fot::io: OctoMap's voxel boundaries lie on multiples of the "
                    "resolution, but the map's origin ") +
        axis + " = " + std::to_string(origin) + " is " + std::to_string(cells) + " cells from 0");
  return std::int32_t(whole);
}

/** Copies every known region of `from` into `to`, keys shifted by `shift`. */
void copyShifted(const FastOctTree& from, FastOctTree& to, const std::int64_t shift[3]) {
  from.forEachRegion([&](const Region& r) {
    const std::int64_t last = (std::int64_t(1) << r.level) - 1;
    const std::int64_t lo[3] = {r.min_key.x + shift[0], r.min_key.y + shift[1], r.min_key.z + shift[2]};
    for (std::int64_t c : lo)
      if (c < kMinKey || c + last > kMaxKey)
        throw std::invalid_argument(
            "pcl::fot::io: the cells lie beyond the key range once moved to the origin");
    to.setBox(Key{std::int32_t(lo[0]), std::int32_t(lo[1]), std::int32_t(lo[2])},
              Key{std::int32_t(lo[0] + last), std::int32_t(lo[1] + last), std::int32_t(lo[2] + last)},
              r.state);
  });
}

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
    for (unsigned o = 0; o < 8; ++o)
      children[o] = node::isBitmap(w) ? node::uniform(node::state(w, o)) : words_[node::childBase(w) + o];
    std::uint32_t codes = 0;
    for (unsigned o = 0; o < 8; ++o) codes |= childCode(children[o]) << (2 * o);
    record(codes);
    for (unsigned o = 0; o < 8; ++o)
      if (childCode(children[o]) == 3) node(children[o], level - 1);
  }

  /** An inner node above the staging tree's root, whose only child (octant `o`) leads towards it. */
  void chain(unsigned o) { record(3u << (2 * o)); }

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

  void node(unsigned depth, const std::int32_t corner[3]) {
    if (end_ - at_ < 2) throw fail("the tree ends early: the file is truncated");
    const std::uint32_t codes = std::uint32_t(at_[0]) | std::uint32_t(at_[1]) << 8;
    at_ += 2;
    const std::int32_t half = std::int32_t(1) << (kDepth - depth - 1);
    for (unsigned o = 0; o < 8; ++o) {
      const unsigned code = (codes >> (2 * o)) & 3u;
      if (code == 0) continue;
      ++nodes_;
      const std::int32_t child[3] = {corner[0] + std::int32_t(o & 1u) * half,
                                     corner[1] + std::int32_t((o >> 1) & 1u) * half,
                                     corner[2] + std::int32_t((o >> 2) & 1u) * half};
      if (code == 3) {
        if (depth + 1 == kDepth) throw fail("a voxel at the deepest level has children");
        node(depth + 1, child);
        continue;
      }
      const Key lo{stagingKey(child[0]), stagingKey(child[1]), stagingKey(child[2])};
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

/** The shortest decimal that reads back as the same double. */
std::string exactDecimal(double v) {
  for (int digits = 6; digits <= 17; ++digits) {
    std::ostringstream s;
    s.precision(digits);
    s << v;
    if (std::stod(s.str()) == v) return s.str();
  }
  return std::to_string(v);
}

}  // namespace

std::string encodeBt(const FastOctTree& tree) {
  const VoxelGrid& grid = tree.getGrid();
  const double res = grid.resolution();
  const std::int64_t shift_to_octomap[3] = {kCentre + cellsFromZero(grid.origin()[0], res, "x"),
                                            kCentre + cellsFromZero(grid.origin()[1], res, "y"),
                                            kCentre + cellsFromZero(grid.origin()[2], res, "z")};
  tree.forEachRegion([&](const Region& r) {
    const std::int64_t last = (std::int64_t(1) << r.level) - 1;
    const std::int64_t k[3] = {r.min_key.x, r.min_key.y, r.min_key.z};
    for (int a = 0; a < 3; ++a)
      if (k[a] + shift_to_octomap[a] < 0 || k[a] + last + shift_to_octomap[a] > 65535)
        throw std::invalid_argument(
            "pcl::fot::io: the map has cells beyond OctoMap's 65536 cells per axis (" +
            std::to_string(kCentre) + " cells either side of coordinate 0)");
  });
  // Staging keys are OctoMap keys minus 0xAAAA (see kStagingBase).
  const std::int64_t shift[3] = {shift_to_octomap[0] - 0xAAAA, shift_to_octomap[1] - 0xAAAA,
                                 shift_to_octomap[2] - 0xAAAA};
  FastOctTree staging(res);
  copyShifted(tree, staging, shift);

  BtWriter writer(staging);
  if (!staging.empty()) {
    // Every cell lies in OctoMap's root cube, so the staging root does too (a tree's root is the smallest
    // aligned cube around what was written); the levels above it are chains of single children.
    const std::array<std::uint32_t, 3>& base = staging.rootBase();
    for (unsigned level = kDepth; level > staging.rootLevel(); --level)
      writer.chain(tree_coord::octant(base[0], base[1], base[2], level));
    writer.node(staging.rootWord(), staging.rootLevel());
  }
  std::string out = std::string(kFirstLine) +
                    "\n# (feel free to add / change comments, but leave the first line as it is!)\n#\n"
                    "id OcTree\nsize " +
                    std::to_string(staging.empty() ? 0 : writer.nodes()) + "\nres " + exactDecimal(res) +
                    "\ndata\n";
  return out + writer.body();
}

void saveBt(const FastOctTree& tree, const std::string& path) {
  writeFileAtomically(path, encodeBt(tree));
}

FastOctTree decodeBt(const char* bytes, std::size_t size, const std::string& name,
                     const BtImportOptions& options) {
  auto fail = [&](const std::string& what) {
    return FormatError("pcl::fot::io: '" + name + "' is not a valid OctoMap .bt file: " + what);
  };
  // The text header: a fixed first line, then keyword lines up to "data".
  std::size_t at = 0;
  auto line = [&](std::string& out) {
    const std::size_t limit = std::min(size, at + 1024);
    std::size_t end = at;
    while (end < limit && bytes[end] != '\n') ++end;
    if (end == limit) throw fail("the header is truncated or has an overlong line");
    out.assign(bytes + at, end - at);
    if (!out.empty() && out.back() == '\r') out.pop_back();
    at = end + 1;
  };
  std::string text;
  line(text);
  if (text.compare(0, sizeof(kFirstLine) - 1, kFirstLine) != 0)
    throw fail("it does not start with '" + std::string(kFirstLine) + "'");
  std::string id;
  double res = std::numeric_limits<double>::quiet_NaN();
  std::uint64_t declared = 0;
  bool has_size = false;
  for (int lines = 0;; ++lines) {
    if (lines > 1000) throw fail("the header has no 'data' line");
    line(text);
    std::istringstream fields(text);
    std::string key;
    fields >> key;
    if (key.empty() || key[0] == '#') continue;
    if (key == "data") break;
    if (key == "id") {
      fields >> id;
    } else if (key == "size") {
      if (!(fields >> declared)) throw fail("the size is not a number");
      has_size = true;
    } else if (key == "res") {
      if (!(fields >> res)) throw fail("the resolution is not a number");
    }
  }
  if (id == "1") id = "OcTree";  // OctoMap's legacy id
  if (id != "OcTree") throw fail("the tree type is '" + id + "'; only OcTree has a .bt form");
  if (!has_size) throw fail("the header has no size");
  if (!(res > 0) || !std::isfinite(res)) throw fail("the resolution is not positive and finite");
  const std::size_t body = size - at;
  // Each inner node takes 2 bytes and has at most 8 children.
  if (declared > 1 + 4 * std::uint64_t(body))
    throw fail("the size " + std::to_string(declared) + " cannot fit the file");

  const std::int32_t origin_cells[3] = {cellsFromZero(options.origin[0], res, "x"),
                                        cellsFromZero(options.origin[1], res, "y"),
                                        cellsFromZero(options.origin[2], res, "z")};
  FastOctTree staging(res), tree(VoxelGrid(res, options.origin[0], options.origin[1], options.origin[2]));
  staging.setMaxMemoryBytes(options.max_pool_bytes);
  tree.setMaxMemoryBytes(options.max_pool_bytes);
  BtReader reader(reinterpret_cast<const unsigned char*>(bytes) + at, body, staging, name);
  if (declared > 0) {
    const std::int32_t root[3] = {0, 0, 0};
    reader.node(0, root);
    if (reader.nodes() != declared)
      throw fail("the tree has " + std::to_string(reader.nodes()) + " nodes, the header says " +
                 std::to_string(declared));
  }
  if (reader.left() != 0) throw fail(std::to_string(reader.left()) + " bytes follow the tree");
  // Staging key + 0xAAAA = OctoMap key = key + 32768 + origin cells.
  const std::int64_t shift[3] = {0xAAAA - kCentre - std::int64_t(origin_cells[0]),
                                 0xAAAA - kCentre - std::int64_t(origin_cells[1]),
                                 0xAAAA - kCentre - std::int64_t(origin_cells[2])};
  copyShifted(staging, tree, shift);
  tree.setMaxMemoryBytes(std::numeric_limits<std::size_t>::max());
  return tree;
}

FastOctTree loadBt(const std::string& path, const BtImportOptions& options) {
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
