#include <pcl_fot/mapping/scan_insertion.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <unordered_set>
#include <vector>

#include <pcl_fot/detail/bits.h>
#include <pcl_fot/detail/worker_threads.h>
#include <pcl_fot/tree/accessor.h>

#include "mapping/block_ray_walker.h"
#include "mapping/ray_bundles.h"
#include "mapping/scan_cells.h"

namespace pcl {
namespace fot {
namespace {

/** Rays a thread takes at a time: neighbours in a scan cross the same blocks, and threads rarely meet. */
constexpr std::size_t kRaysPerRun = 2048;
/** Fewer rays than this a thread are walked on fewer threads: starting one costs more than it saves. */
constexpr std::size_t kRaysPerShare = 4096;

/** Calls `visit(const Key&)` for each cell of the walker's stretch `i`. */
template <typename Visit>
void forEachCell(const detail::BlockRayWalker& walker, std::size_t i, Visit&& visit) {
  std::uint32_t block[3];
  walker.block(walker.blockKey(i), block);
  for (std::uint64_t cells = walker.cells(i); cells != 0; cells &= cells - 1)
    visit(detail::block_cells::cellKey(block, detail::lowestBit(cells)));
}

/** A ray may step one cell past its end keys; keep those cells inside the key range too. */
bool traceable(const Key& k) {
  return k.x > kMinKey && k.x < kMaxKey && k.y > kMinKey && k.y < kMaxKey && k.z > kMinKey && k.z < kMaxKey;
}

/**
 * Which rays can pass a cell of the scan's region. A ray's walk starts in the sensor's cell and steps, on
 * each axis, only the way the ray points, so its cells lie between the sensor's cell and the end's (a cell
 * or two past the end, see traceable). Within that box it passes only cells the segment meets, give or take
 * the walk's rounding: its float direction strays by about 1e-7 of the length. The test against the region
 * widens it by a tenth of a cell plus 1e-6 of the ray's length, and lengthens the segment by two cells.
 */
class RegionCull {
 public:
  RegionCull(const CellGrid& grid, const float sensor[3], const Key& sensor_key,
             const std::optional<KeyBox>& region)
      : region_(region), sensor_key_{sensor_key.x, sensor_key.y, sensor_key.z} {
    if (!region) return;
    const double res = grid.resolution(), margin = 0.1 * res;
    const std::int32_t lo[3] = {region->min.x, region->min.y, region->min.z};
    const std::int32_t hi[3] = {region->max.x, region->max.y, region->max.z};
    for (unsigned a = 0; a < 3; ++a) {
      sensor_[a] = sensor[a];
      key_lo_[a] = lo[a], key_hi_[a] = hi[a];
      lo_[a] = grid.origin()[a] + double(lo[a]) * res - margin;
      hi_[a] = grid.origin()[a] + (double(hi[a]) + 1.0) * res + margin;
    }
    extra_ = 2.0 * res;
  }

  bool reaches(const float end[3], const Key& end_key) const {
    if (!region_) return true;
    const std::int32_t e[3] = {end_key.x, end_key.y, end_key.z};
    for (unsigned a = 0; a < 3; ++a) {
      const std::int32_t s = sensor_key_[a];
      const std::int32_t lo = e[a] > s ? s : e[a] - 2, hi = e[a] < s ? s : e[a] + 2;
      if (lo > key_hi_[a] || hi < key_lo_[a]) return false;
    }
    double d[3], length = 0.0;
    for (unsigned a = 0; a < 3; ++a) {
      d[a] = double(end[a]) - sensor_[a];
      length += d[a] * d[a];
    }
    length = std::sqrt(length);
    const double widen = 1e-6 * length;
    double t0 = 0.0, t1 = length > 0.0 ? 1.0 + extra_ / length : 1.0;
    for (unsigned a = 0; a < 3; ++a) {
      const double lo = lo_[a] - widen, hi = hi_[a] + widen;
      if (d[a] == 0.0) {
        if (sensor_[a] < lo || sensor_[a] > hi) return false;
        continue;
      }
      double near = (lo - sensor_[a]) / d[a], far = (hi - sensor_[a]) / d[a];
      if (near > far) std::swap(near, far);
      t0 = std::max(t0, near);
      t1 = std::min(t1, far);
    }
    return t0 <= t1;
  }

 private:
  const std::optional<KeyBox>& region_;
  std::int32_t sensor_key_[3];
  std::int32_t key_lo_[3] = {0, 0, 0}, key_hi_[3] = {0, 0, 0};
  double sensor_[3] = {0, 0, 0}, lo_[3] = {0, 0, 0}, hi_[3] = {0, 0, 0}, extra_ = 0.0;
};

/** A scan's rays, checked: each ends at a valid key that keeps its cells inside the key range. */
struct ScanRays {
  std::vector<float> ends;  // xyz of each ray's end that the walker reaches
  std::vector<float> far;   // the ends of rays too long for the walker's words (see BlockRayWalker::kReach)
  std::vector<Key> endpoints;  // the cells of the rays that end at their point
};

/** The scan's points checked and made `rays`; bad points are counted in `stats` and left out. */
void prepareRays(const CellGrid& grid, const float sensor[3], const float* xyz, std::size_t count,
                 std::size_t stride_bytes, const ScanOptions& options, ScanStats& stats, ScanRays& rays) {
  if (!std::isfinite(sensor[0]) || !std::isfinite(sensor[1]) || !std::isfinite(sensor[2]))
    throw std::invalid_argument("pcl::fot::insertRays: the sensor position is not finite");
  Key sensor_key;
  if (!grid.pointToKey(sensor[0], sensor[1], sensor[2], sensor_key) || !traceable(sensor_key))
    throw std::out_of_range("pcl::fot::insertRays: the sensor lies beyond the key range");

  const RegionCull cull(grid, sensor, sensor_key, options.region);
  rays.ends.clear();
  rays.far.clear();
  rays.endpoints.clear();
  rays.ends.reserve(3 * count);
  const auto addRay = [&](const float* end, const Key& end_key) {
    std::vector<float>& to = detail::BlockRayWalker::reaches(sensor_key, end_key) ? rays.ends : rays.far;
    to.insert(to.end(), end, end + 3);
    ++stats.rays;
  };
  rays.endpoints.reserve(count);
  std::unordered_set<Key, KeyHash> seen;  // the cells of the points so far, with discretize
  const char* bytes = reinterpret_cast<const char*>(xyz);
  for (std::size_t i = 0; i < count; ++i) {
    const float* p = reinterpret_cast<const float*>(bytes + i * stride_bytes);
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      ++stats.non_finite;
      continue;
    }
    float centre[3];
    if (options.discretize) {  // OctoMap's computeDiscreteUpdate: each cell once, its centre as a float
      Key k;
      if (!grid.pointToKey(p[0], p[1], p[2], k)) {
        ++stats.out_of_range;
        continue;
      }
      if (!seen.insert(k).second) {
        ++stats.merged;
        continue;
      }
      const std::int32_t key[3] = {k.x, k.y, k.z};
      for (unsigned a = 0; a < 3; ++a) centre[a] = float(grid.keyToCoord(key[a], a));
      p = centre;
    }
    // OctoMap's arithmetic: a float difference, its squared norm summed in float.
    const float d[3] = {p[0] - sensor[0], p[1] - sensor[1], p[2] - sensor[2]};
    const double dist = std::sqrt(double(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
    if (dist < options.min_range) {
      ++stats.too_close;
      continue;
    }
    if (options.max_range > 0.0 && dist > options.max_range) {
      const float len = float(dist), range = float(options.max_range);
      const float end[3] = {sensor[0] + d[0] / len * range, sensor[1] + d[1] / len * range,
                            sensor[2] + d[2] / len * range};
      Key end_key;
      if (!grid.pointToKey(end[0], end[1], end[2], end_key) || !traceable(end_key)) {
        ++stats.out_of_range;
        continue;
      }
      if (!cull.reaches(end, end_key)) {
        ++stats.outside_region;
        continue;
      }
      addRay(end, end_key);
      ++stats.truncated;
      continue;
    }
    Key key;
    if (!grid.pointToKey(p[0], p[1], p[2], key) || !traceable(key)) {
      ++stats.out_of_range;
      continue;
    }
    if (!cull.reaches(p, key)) {
      ++stats.outside_region;
      continue;
    }
    addRay(p, key);
    if (!options.region || options.region->contains(key)) rays.endpoints.push_back(key);
  }
  stats.occupied = rays.endpoints.size();
}

/**
 * The tree's side. With LineBurstAccess, the rays' cells come a 4×4×4 block at a time, and a table
 * remembers the blocks written lately: neighbouring rays cross the same blocks again and again, and the
 * table answers for them. A block's first leaf is written at once, so that a cube the tree reports free
 * already is passed without touching it: the last visited node answers for the next cells. The block's
 * other cells wait in the table and go into the tree a block at a time, when another block takes the slot,
 * the block is all free, or the rays are done: one short access per leaf instead of one from wherever the
 * last ray was. Phase 1 only ever adds free cells, so a cube found free stays free. Without
 * LineBurstAccess, every cell is its own access from the root.
 */
class TreeWriter {
 public:
  /** `rays`, the scan's size, sizes the table of written blocks: one entry per ray, 2^10 to 2^16. */
  TreeWriter(FastOctTree& t, bool line_burst, std::size_t rays)
      : accessor_(t, line_burst), line_burst_(line_burst) {
    if (!line_burst) return;
    while (written_bits_ < 16 && (std::size_t(1) << written_bits_) < rays) ++written_bits_;
    written_.resize(std::size_t(1) << written_bits_);
  }

  /** The walker's batch of `n` stretches. */
  void freeStretches(const detail::BlockRayWalker& walker, std::size_t n) {
    if (!line_burst_) {
      for (std::size_t i = 0; i < n; ++i) forEachCell(walker, i, [&](const Key& k) { freeCell(k); });
      return;
    }
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint64_t key = walker.blockKey(i), cells = walker.cells(i);
      if (((key ^ cube_key_) & cube_mask_) == 0) continue;
      Written& w = written_[(key * 0x9E3779B97F4A7C15u) >> (64 - written_bits_)];
      if (w.key != key) {
        replace(walker, w, key, cells);
        continue;
      }
      const std::uint64_t fresh = cells & ~w.cells;
      w.pending |= fresh;
      w.cells |= cells;
      // A block that just filled goes to the tree now, which folds it. Rays keep crossing full blocks, so
      // one branch tests both conditions: it is rarely taken and easy to predict.
      if ((~w.cells | std::uint64_t(fresh == 0)) == 0) flush(walker, w);
    }
  }

  /** Writes the cells still waiting in the table; the rays' free cells are all in the tree afterwards. */
  void finishFree(const detail::BlockRayWalker& walker) {
    for (Written& w : written_) flush(walker, w);
  }

  void freeCell(const Key& k) { accessor_.setValidCell(k, CellState::Free); }
  void occupied(const Key& k) { accessor_.setValidCell(k, CellState::Occupied); }

 private:
  /** Cells this writer made free in one 4×4×4 block: they stay free until the scan's endpoints. */
  struct Written {
    std::uint64_t key = ~std::uint64_t(0);  // the walker's block key; no block has this one
    std::uint64_t cells = 0;                // see detail::block_cells
    std::uint64_t pending = 0;              // the subset not written to the tree yet
  };

  /** Takes a new block into its slot, whose block goes to the tree; off the hot path of blocks seen. */
  __attribute__((noinline)) void replace(const detail::BlockRayWalker& walker, Written& w, std::uint64_t key,
                                         std::uint64_t cells) {
    flush(walker, w);
    w.key = key;
    w.cells = cells;
    const unsigned leaf = detail::block_cells::leafOf(detail::lowestBit(cells));
    w.pending = cells & ~detail::block_cells::leafBits(leaf);
    std::uint32_t block[3];
    walker.block(key, block);
    const unsigned skip =
        accessor_.setValidLeafCells(detail::block_cells::leafKey(block, leaf),
                                    detail::block_cells::leafMask(cells, leaf), CellState::Free);
    if (skip < 2) return;  // the cube must hold whole blocks
    cube_key_ = key;
    cube_mask_ = detail::BlockRayWalker::cubeMask(skip);
  }

  void flush(const detail::BlockRayWalker& walker, Written& w) {
    if (w.pending == 0) return;
    std::uint32_t block[3];
    walker.block(w.key, block);
    for (std::uint64_t p = w.pending; p != 0;) {
      const unsigned leaf = detail::block_cells::leafOf(detail::lowestBit(p));
      accessor_.setValidLeafCells(detail::block_cells::leafKey(block, leaf),
                                  detail::block_cells::leafMask(p, leaf), CellState::Free);
      p &= ~detail::block_cells::leafBits(leaf);
    }
    w.pending = 0;
  }

  Accessor accessor_;
  bool line_burst_;
  // A cube the tree holds free: the blocks whose keys match cube_key_ on cube_mask_ (none at first).
  std::uint64_t cube_key_ = ~std::uint64_t(0), cube_mask_ = ~std::uint64_t(0);
  unsigned written_bits_ = 10;
  std::vector<Written> written_;
};

class GridWriter {
 public:
  explicit GridWriter(FastOccMesh& g) : grid_(g) {}
  void freeStretches(const detail::BlockRayWalker& walker, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) forEachCell(walker, i, [&](const Key& k) { freeCell(k); });
  }
  void finishFree(const detail::BlockRayWalker&) {}
  void freeCell(const Key& k) {
    if (grid_.contains(k)) grid_.setCell(k, CellState::Free);
  }
  void occupied(const Key& k) {
    if (grid_.contains(k)) grid_.setCell(k, CellState::Occupied);
  }

 private:
  FastOccMesh& grid_;
};

/** Walks the rays on this thread, handing their cells to `writer` as they come. */
template <typename Writer>
void streamCells(Writer& writer, const CellGrid& grid, const float sensor[3], const ScanRays& rays,
                 ScanStats& stats) {
  detail::BlockRayWalker walker(grid, sensor, rays.ends.data(), rays.ends.size() / 3);
  while (const std::size_t n = walker.next()) writer.freeStretches(walker, n);
  writer.finishFree(walker);
  stats.ray_cells = walker.cellCount();
  for (std::size_t i = 0; i < rays.far.size(); i += 3)
    stats.ray_cells += traceSegment(grid, sensor, &rays.far[i], [&](const Key& k) { writer.freeCell(k); });
  // Endpoints last: within a scan, occupied wins over free.
  for (const Key& k : rays.endpoints) writer.occupied(k);
}

/**
 * One share of a scan's rays walked, and their cells gathered, each once (ScanCells). Neighbouring rays cross
 * the same blocks: a small table of the walker's block keys, in cache, answers most stretches before the
 * scan's table is probed.
 */
class CellGatherer {
 public:
  CellGatherer() : cells_(0), recent_(kRecent) {}

  /** Empties it for a share of about `rays` rays; keeps its buffers. */
  void reset(std::size_t rays) {
    cells_.reset(rays < 1024 ? 1024 : rays);
    std::fill(recent_.begin(), recent_.end(), Recent{});
    walked_ = skipped_ = 0;
  }

  /** Walks `count` rays, their ends as xyz triples, each from its cut; counts the cells walked and skipped.
   */
  void walk(const CellGrid& grid, const float sensor[3], const float* ends, const double* cuts,
            std::size_t count) {
    detail::BlockRayWalker walker(grid, sensor, ends, cuts, count);
    while (const std::size_t n = walker.next()) {
      for (std::size_t i = 0; i < n; ++i) {
        const std::uint64_t key = walker.blockKey(i);
        Recent& r = recent_[(key * 0x9E3779B97F4A7C15u) >> (64 - kRecentBits)];
        if (r.key != key) {
          std::uint32_t block[3];
          walker.block(key, block);
          r = Recent{key, cells_.index(block)};
        }
        cells_.pass(r.index, walker.cells(i));
      }
    }
    walked_ += walker.cellCount();
    skipped_ += walker.skippedCount();
  }

  /** Adds cells passed (RayBundles' blocks). */
  void pass(const std::vector<ScanBlock>& blocks) {
    std::uint32_t last[3] = {~0u, ~0u, ~0u}, index = 0;
    for (const ScanBlock& b : blocks) {
      if (b.at[0] != last[0] || b.at[1] != last[1] || b.at[2] != last[2]) {
        index = cells_.index(b.at);
        std::copy(b.at, b.at + 3, last);
      }
      cells_.pass(index, b.passed);
    }
  }

  std::uint64_t walked() const { return walked_; }
  std::uint64_t skipped() const { return skipped_; }

  detail::ScanCells& cells() { return cells_; }

 private:
  struct Recent {
    std::uint64_t key = ~std::uint64_t(0);  // no block has this key
    std::uint32_t index = 0;
  };
  static constexpr unsigned kRecentBits = 12;
  static constexpr std::size_t kRecent = std::size_t(1) << kRecentBits;

  detail::ScanCells cells_;
  std::vector<Recent> recent_;
  std::uint64_t walked_ = 0, skipped_ = 0;
};

/**
 * What inserting a scan allocates, kept for the calling thread's next scan: a sequence of scans allocates it
 * once instead of touching fresh pages for every scan, which on two threads cost more than the second
 * thread gave. A scan of far fewer points than the largest one so far lets it go.
 */
struct ScanScratch {
  ScanRays rays;
  detail::RayBundler bundler;
  std::vector<std::unique_ptr<CellGatherer>> shares;  // one a worker
  std::size_t points = 0;                             // the largest scan's since it was made
};

ScanScratch& scratchFor(std::size_t points) {
  constexpr std::size_t kKeptAnyway = 1 << 16;
  thread_local std::unique_ptr<ScanScratch> scratch;
  if (!scratch || scratch->points > 4 * points + kKeptAnyway) scratch = std::make_unique<ScanScratch>();
  scratch->points = std::max(scratch->points, points);
  return *scratch;
}

/**
 * The scan's cells, each once, as OctoMap's computeUpdate collects them. The rays are cut into runs that
 * `workers` threads take in turn, each gathering the cells of its runs; their cells are then joined. A cell's
 * update depends only on whether some ray passes it or ends in it, so the cells are the same for any count.
 */
const detail::ScanCells& gatherCells(const CellGrid& grid, const float sensor[3], ScanScratch& scratch,
                                     const detail::RayBundles& bundles, std::size_t workers,
                                     ScanStats& stats) {
  const ScanRays& rays = scratch.rays;
  const std::size_t count = rays.ends.size() / 3, runs = (count + kRaysPerRun - 1) / kRaysPerRun;
  std::vector<std::unique_ptr<CellGatherer>>& shares = scratch.shares;
  if (shares.size() < workers) shares.resize(workers);
  std::atomic<std::size_t> next_run{0};
  detail::runWorkers(workers, [&](std::size_t w) {
    if (!shares[w]) shares[w] = std::make_unique<CellGatherer>();
    shares[w]->reset(count / workers);
    if (w == 0) shares[w]->pass(bundles.blocks);
    for (std::size_t r; (r = next_run.fetch_add(1, std::memory_order_relaxed)) < runs;) {
      const std::size_t begin = r * kRaysPerRun, n = std::min(kRaysPerRun, count - begin);
      shares[w]->walk(grid, sensor, rays.ends.data() + 3 * begin,
                      bundles.cuts.empty() ? nullptr : bundles.cuts.data() + begin, n);
    }
  });
  detail::ScanCells& cells = shares[0]->cells();
  for (std::size_t w = 0; w < workers; ++w) {
    stats.ray_cells += shares[w]->walked();
    stats.skipped_cells += shares[w]->skipped();
    if (w > 0) cells.join(shares[w]->cells());
  }
  for (std::size_t i = 0; i < rays.far.size(); i += 3)
    stats.ray_cells += traceSegment(grid, sensor, &rays.far[i], [&](const Key& k) { cells.pass(k); });
  for (const Key& k : rays.endpoints) cells.hit(k);
  return cells;
}

/** The cells of a 4×4×4 block (see detail::block_cells) inside the scan's region: all without one. */
class RegionMask {
 public:
  explicit RegionMask(const std::optional<KeyBox>& region) : all_(!region) {
    if (region) lo_ = TreeCoord(region->min), hi_ = TreeCoord(region->max);
  }

  std::uint64_t operator()(const std::uint32_t (&block)[3]) const {
    if (all_) return ~std::uint64_t(0);
    unsigned axis[3] = {0, 0, 0};
    for (unsigned a = 0; a < 3; ++a)
      for (unsigned d = 0; d < 4; ++d) {
        const std::uint32_t c = 4 * block[a] + d;
        axis[a] |= unsigned(c >= lo_[a] && c <= hi_[a]) << d;
      }
    std::uint64_t plane = 0, cube = 0;  // cell bit x + 4y + 16z
    for (unsigned y = 0; y < 4; ++y)
      if ((axis[1] >> y) & 1u) plane |= std::uint64_t(axis[0]) << (4 * y);
    for (unsigned z = 0; z < 4; ++z)
      if ((axis[2] >> z) & 1u) cube |= plane << (16 * z);
    return cube;
  }

 private:
  bool all_;
  TreeCoord lo_, hi_;
};

/**
 * Writes the scan's cells a leaf at a time, in the order the rays first reached their blocks, which keeps
 * LineBurstAccess's paths short: `write(leaf key, miss mask, hit mask)` returns what
 * Accessor::setValidLeafCells returns. A block whose every cell is missed goes to `accessor.missBlock`
 * first, which writes it whole where the tree holds it as one cube. A block without endpoints changes
 * nothing in a settled free cube, so when the tree reports one around a leaf, the blocks after it that lie
 * in that cube and have no endpoint are passed over: the last visited node answers for them. Returns the
 * cells marked free.
 */
template <typename Write>
std::uint64_t writeCells(const ScanBlock* blocks, std::size_t count, const RegionMask& region,
                         Accessor& accessor, bool log_odds, Write&& write) {
  std::uint32_t cube[3] = {0, 0, 0};
  unsigned cube_shift = 32;  // no cube yet
  std::uint64_t free = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const ScanBlock& block = blocks[i];
    const std::uint64_t inside = region(block.at);
    const detail::ScanCells::Block b{
        {block.at[0], block.at[1], block.at[2]}, block.passed & inside, block.hit & inside};
    const std::uint64_t miss = b.passed & ~b.hit;
    free += std::uint64_t(__builtin_popcountll(miss));
    if ((b.passed | b.hit) == 0) continue;
    if (b.hit == 0 && cube_shift < 32 &&
        ((b.at[0] ^ cube[0]) | (b.at[1] ^ cube[1]) | (b.at[2] ^ cube[2])) >> cube_shift == 0)
      continue;
    if (miss == ~std::uint64_t(0)) {
      const unsigned skip = accessor.missBlock(detail::block_cells::leafKey(b.at, 0), log_odds);
      if (skip != Accessor::kByLeaves) {
        if (skip >= 2) {  // a settled free cube of whole blocks: this one and those in it
          cube_shift = skip - 2;
          for (int a = 0; a < 3; ++a) cube[a] = b.at[a];
        }
        continue;
      }
    }
    for (std::uint64_t p = miss | b.hit; p != 0;) {
      const unsigned leaf = detail::block_cells::leafOf(detail::lowestBit(p));
      const unsigned skip =
          write(detail::block_cells::leafKey(b.at, leaf), detail::block_cells::leafMask(miss, leaf),
                detail::block_cells::leafMask(b.hit, leaf));
      p &= ~detail::block_cells::leafBits(leaf);
      if (skip >= 2 && b.hit == 0) {  // a settled free cube of whole blocks: this one and those in it
        cube_shift = skip - 2;
        for (int a = 0; a < 3; ++a) cube[a] = b.at[a];
        break;
      }
    }
  }
  return free;
}

}  // namespace

ScanStats insertRays(FastOctTree& map, const float sensor[3], const float* xyz, std::size_t count,
                     std::size_t stride_bytes, const ScanOptions& options) {
  const CellGrid& grid = map.getGrid();
  ScanStats stats;
  ScanScratch& scratch = scratchFor(count);
  const ScanRays& rays = scratch.rays;
  prepareRays(grid, sensor, xyz, count, stride_bytes, options, stats, scratch.rays);
  const bool log_odds = options.rule.value_or(map.getUpdateRule()) == UpdateRule::LogOdds;
  const std::size_t workers = detail::workerCount(options.threads, rays.ends.size() / 3 / kRaysPerShare);
  const detail::RayBundles& bundles =
      scratch.bundler.bundle(grid, sensor, rays.ends.data(), rays.ends.size() / 3, workers);
  // A binary scan whose rays are walked whole is written as it is walked: no gathering.
  if (!log_odds && workers == 1 && !options.region && bundles.cuts.empty()) {
    TreeWriter writer(map, options.line_burst, count);
    streamCells(writer, grid, sensor, rays, stats);
    return stats;
  }
  const detail::ScanCells& cells = gatherCells(grid, sensor, scratch, bundles, workers, stats);
  stats.free_cells = applyScan(map, cells.blocks().data(), cells.blocks().size(), options);
  return stats;
}

std::vector<ScanBlock> traceScan(const FastOctTree& map, const float sensor[3], const float* xyz,
                                 std::size_t count, std::size_t stride_bytes, const ScanOptions& options,
                                 ScanStats* stats) {
  ScanStats own;
  ScanStats& s = stats ? *stats : own;
  s = ScanStats{};
  ScanScratch& scratch = scratchFor(count);
  const ScanRays& rays = scratch.rays;
  prepareRays(map.getGrid(), sensor, xyz, count, stride_bytes, options, s, scratch.rays);
  const std::size_t workers = detail::workerCount(options.threads, rays.ends.size() / 3 / kRaysPerShare);
  const detail::RayBundles& bundles =
      scratch.bundler.bundle(map.getGrid(), sensor, rays.ends.data(), rays.ends.size() / 3, workers);
  return gatherCells(map.getGrid(), sensor, scratch, bundles, workers, s).blocks();
}

std::uint64_t applyScan(FastOctTree& map, const ScanBlock* blocks, std::size_t count,
                        const ScanOptions& options) {
  Accessor accessor(map, options.line_burst);
  const RegionMask region(options.region);
  if (options.rule.value_or(map.getUpdateRule()) == UpdateRule::LogOdds)
    return writeCells(blocks, count, region, accessor, true,
                      [&](const Key& k, std::uint32_t miss, std::uint32_t hit) {
                        return accessor.updateLeaf(k, miss, hit);
                      });
  return writeCells(blocks, count, region, accessor, false,
                    [&](const Key& k, std::uint32_t free, std::uint32_t occupied) {
                      const unsigned skip = free ? accessor.setValidLeafCells(k, free, CellState::Free) : 0;
                      if (occupied) accessor.setValidLeafCells(k, occupied, CellState::Occupied);
                      return skip;
                    });
}

ScanStats insertRays(FastOccMesh& map, const float sensor[3], const float* xyz, std::size_t count,
                     std::size_t stride_bytes, const ScanOptions& options) {
  if (options.rule == UpdateRule::LogOdds)
    throw std::invalid_argument(
        "pcl::fot::insertRays: the dense grid keeps no log-odds; use the Binary rule");
  if (options.region)
    throw std::invalid_argument("pcl::fot::insertRays: the dense grid maps no region; map the whole grid");
  ScanStats stats;
  ScanRays& rays = scratchFor(count).rays;
  prepareRays(map.getGrid(), sensor, xyz, count, stride_bytes, options, stats, rays);
  GridWriter writer(map);
  streamCells(writer, map.getGrid(), sensor, rays, stats);
  return stats;
}

}  // namespace fot
}  // namespace pcl
