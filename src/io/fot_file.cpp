#include <pcl_fot/io/fot_file.h>

#include <cmath>
#include <cstring>

#include <boost/crc.hpp>

#include <pcl_fot/io/file_io.h>

#include "io/region_copy.h"

namespace pcl {
namespace fot {
namespace io {
namespace {

// "\x89FOT\r\n\x1a\n": a high byte, then line endings and a DOS end-of-file, so that a file mangled as text
// fails at once (the PNG trick).
constexpr char kMagic[8] = {'\x89', 'F', 'O', 'T', '\r', '\n', '\x1a', '\n'};
constexpr std::size_t kHeaderBytes = 152;
constexpr std::size_t kV2HeaderBytes = 96;  // versions 1 and 2: no rule, sensor model or values
constexpr std::size_t kChecksumBytes = 4;

void put32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(char((v >> (8 * i)) & 0xFFu));
}
void put64(std::string& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(char((v >> (8 * i)) & 0xFFu));
}
void putDouble(std::string& out, double d) {
  std::uint64_t bits;
  std::memcpy(&bits, &d, 8);
  put64(out, bits);
}
std::uint32_t get32(const unsigned char* p) {
  return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 |
         std::uint32_t(p[3]) << 24;
}
std::uint64_t get64(const unsigned char* p) {
  return std::uint64_t(get32(p)) | std::uint64_t(get32(p + 4)) << 32;
}
double getDouble(const unsigned char* p) {
  const std::uint64_t bits = get64(p);
  double d;
  std::memcpy(&d, &bits, 8);
  return d;
}

/** Version 1 placed its nodes at keys + 0x2AAAAAAA, today's tree coordinates less 0x2AAA cells. */
constexpr unsigned kLegacyVersion = 1;
constexpr std::int64_t kLegacyOffset = 0x2AAA;

/** A version-1 map read as today's sits 0x2AAA cells off on each axis: its cells, moved back. */
FastOctTree fromLegacyCoordinates(const FastOctTree& read, std::size_t max_pool_bytes) {
  const std::int64_t shift[3] = {-kLegacyOffset, -kLegacyOffset, -kLegacyOffset};
  return shiftedCopy(read, read.getGrid(), shift, max_pool_bytes);
}

std::uint32_t crc32(const char* data, std::size_t size) {
  boost::crc_32_type crc;
  crc.process_bytes(data, size);
  return crc.checksum();
}

}  // namespace

std::string encodeFot(const FastOctTree& tree) {
  const FastOctTree::CanonicalPool pool = tree.canonicalPool();
  const CellGrid& grid = tree.getGrid();
  const std::uint64_t blocks = pool.words.size() / 8 - 1;
  std::string out(kMagic, sizeof(kMagic));
  out.reserve(kHeaderBytes + (pool.words.size() + pool.values.size()) * 4 + kChecksumBytes);
  put32(out, kFotVersion);
  put32(out, std::uint32_t(kHeaderBytes));
  putDouble(out, grid.resolution());
  for (int a = 0; a < 3; ++a) putDouble(out, grid.origin()[a]);
  put32(out, pool.root_level);
  for (std::uint32_t b : pool.root_base.u) put32(out, b);
  put64(out, 1 + 8 * blocks);
  put64(out, blocks);
  put64(out, tree.getOccupiedCount());
  put64(out, tree.getFreeCount());
  put32(out, std::uint32_t(tree.getUpdateRule()));
  put32(out, 0);
  const SensorModel& m = pool.model;
  for (double p : {m.probHit(), m.probMiss(), m.clampMin(), m.clampMax(), m.occupancy()}) putDouble(out, p);
  put64(out, pool.values.size() / 8);
  for (NodeWord w : pool.words) put32(out, w);
  for (float v : pool.values) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, 4);
    put32(out, bits);
  }
  put32(out, crc32(out.data(), out.size()));
  return out;
}

FastOctTree decodeFot(const char* bytes, std::size_t size, const std::string& name,
                      std::size_t max_pool_bytes) {
  auto fail = [&](const std::string& what) -> FormatError {
    return FormatError("pcl::fot::io: '" + name + "' is not a valid .fot map: " + what);
  };
  const auto* p = reinterpret_cast<const unsigned char*>(bytes);
  if (size < sizeof(kMagic) || std::memcmp(bytes, kMagic, sizeof(kMagic)) != 0)
    throw fail("it does not start with the .fot magic bytes");
  if (size < 16) throw fail("it ends inside the header (" + std::to_string(size) + " bytes)");
  const std::uint32_t version = get32(p + 8), header = get32(p + 12);
  if (version < kLegacyVersion || version > kFotVersion)
    throw fail("format version " + std::to_string(version) + "; this build reads versions " +
               std::to_string(kLegacyVersion) + " to " + std::to_string(kFotVersion));
  const std::size_t header_bytes = version == kFotVersion ? kHeaderBytes : kV2HeaderBytes;
  if (header != header_bytes)
    throw fail("a header of " + std::to_string(header) + " bytes, not " + std::to_string(header_bytes));
  if (size < header_bytes) throw fail("it ends inside the header (" + std::to_string(size) + " bytes)");
  const double res = getDouble(p + 16), ox = getDouble(p + 24), oy = getDouble(p + 32),
               oz = getDouble(p + 40);
  const std::string bad_grid = CellGrid::whyInvalid(res, ox, oy, oz);
  if (!bad_grid.empty()) throw fail(bad_grid);
  FastOctTree::CanonicalPool pool;
  pool.root_level = get32(p + 48);
  pool.root_base = {get32(p + 52), get32(p + 56), get32(p + 60)};
  const std::uint64_t nodes = get64(p + 64), blocks = get64(p + 72), occupied = get64(p + 80),
                      free = get64(p + 88);
  if (blocks > node::kMaxBlocks) throw fail("it claims " + std::to_string(blocks) + " blocks");
  if (nodes != 1 + 8 * blocks) throw fail("the node count does not match the block count");
  UpdateRule rule = UpdateRule::Binary;
  std::uint64_t leaves = 0;  // leaves with values
  if (version == kFotVersion) {
    const std::uint32_t r = get32(p + 96);
    if (r > 1) throw fail("the update rule " + std::to_string(r) + " is unknown");
    if (get32(p + 100) != 0) throw fail("the header's padding after the update rule is not zero");
    rule = UpdateRule(r);
    try {
      pool.model = SensorModel(getDouble(p + 104), getDouble(p + 112), getDouble(p + 120), getDouble(p + 128),
                               getDouble(p + 136));
    } catch (const std::invalid_argument& e) {
      throw fail(e.what());
    }
    leaves = get64(p + 144);
    if (leaves > 8 * (blocks + 1)) throw fail("it claims more leaves with values than its pool has words");
  }
  // Sizes are checked against the real file before anything is allocated.
  const std::uint64_t pool_bytes = (blocks + 1) * 32, value_bytes = leaves * 32;
  if (pool_bytes + value_bytes > max_pool_bytes)
    throw fail("its pool and values of " + std::to_string(pool_bytes + value_bytes) +
               " bytes exceed the loader's cap of " + std::to_string(max_pool_bytes));
  const std::uint64_t expected = header_bytes + pool_bytes + value_bytes + kChecksumBytes;
  if (size != expected)
    throw fail(std::string(size < expected ? "it is truncated: " : "it has trailing bytes: ") +
               std::to_string(size) + " bytes where the header promises " + std::to_string(expected));
  if (crc32(bytes, size - kChecksumBytes) != get32(p + size - kChecksumBytes))
    throw fail("the checksum does not match: the file is corrupted");
  pool.words.resize(std::size_t(blocks + 1) * 8);
  for (std::size_t i = 0; i < pool.words.size(); ++i) pool.words[i] = get32(p + header_bytes + 4 * i);
  pool.values.resize(std::size_t(leaves) * 8);
  const unsigned char* values = p + header_bytes + pool_bytes;
  for (std::size_t i = 0; i < pool.values.size(); ++i) {
    const std::uint32_t bits = get32(values + 4 * i);
    std::memcpy(&pool.values[i], &bits, 4);
  }
  try {
    FastOctTree tree =
        FastOctTree::fromCanonicalPool(CellGrid(res, ox, oy, oz), std::move(pool), max_pool_bytes);
    tree.setUpdateRule(rule);
    if (tree.getOccupiedCount() != occupied || tree.getFreeCount() != free)
      throw fail("the cell counts in the header do not match the tree");
    if (version == kLegacyVersion) return fromLegacyCoordinates(tree, max_pool_bytes);
    return tree;
  } catch (const std::invalid_argument& e) {
    throw fail(e.what());
  }
}

void saveFot(const FastOctTree& tree, const std::string& path) {
  writeFileAtomically(path, encodeFot(tree));
}

FastOctTree loadFot(const std::string& path, std::size_t max_pool_bytes) {
  std::string bytes;
  try {  // no larger than a valid header could promise: a huge file is refused before it is read
    bytes = readFile(path, kHeaderBytes + max_pool_bytes + kChecksumBytes);
  } catch (const std::length_error& e) {
    throw FormatError(e.what());
  }
  return decodeFot(bytes.data(), bytes.size(), path, max_pool_bytes);
}

}  // namespace io
}  // namespace fot
}  // namespace pcl
