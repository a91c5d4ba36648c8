#include <pcl_fot/search/point_index.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <variant>

#include <pcl_fot/tree/accessor.h>

#include "search/cell_size.h"
#include "search/neighbour_walk.h"
#include "search/point_policy.h"

namespace pcl {
namespace fot {
namespace {

bool finite3(const float* p) {
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

/** The key of the points' centre: tree coordinate 0x2AAAAAAA, halfway between level boundaries. */
constexpr std::int32_t kCentreKey = 0x2AAA;

std::atomic<std::uint64_t> next_build_id{1};
constexpr std::uint32_t kNoSlot = ~std::uint32_t(0);
/** The bucket of the outliers in an updated index: a key no cell has. */
constexpr Key kOutliers{std::numeric_limits<std::int32_t>::min(), 0, 0};

/**
 * The key of coordinate c on one axis, as CellGrid::pointToKey computes it, or one past the key range's end
 * on the side c lies when it is beyond the range: keys grow with coordinates.
 */
std::int64_t stretchedKey(const CellGrid& grid, double c, unsigned axis) {
  const double q = (c - grid.origin()[axis]) / grid.resolution();
  if (q < double(kMinKey)) return std::int64_t(kMinKey) - 1;
  if (q >= double(kMaxKey) + 1.0) return std::int64_t(kMaxKey) + 1;
  return std::int64_t(std::floor(q));
}

}  // namespace

PointIndex::PointIndex() : automatic_(true), resolution_(0.01), tree_(resolution_) {}

PointIndex::PointIndex(double resolution) : automatic_(false), resolution_(resolution), tree_(resolution) {}

/** The points given to build: input point j is the cloud's point subset[j], or its point j. */
class PointIndex::Input {
 public:
  Input(const float* xyz, std::size_t count, std::size_t stride_bytes, const std::int32_t* subset,
        std::size_t subset_size)
      : bytes_(reinterpret_cast<const char*>(xyz)),
        count_(count),
        stride_(stride_bytes),
        subset_(subset),
        size_(subset ? subset_size : count) {}

  std::size_t size() const { return size_; }
  const float* data() const { return reinterpret_cast<const float*>(bytes_); }
  std::size_t stride() const { return stride_; }
  const float* point(std::size_t i) const { return reinterpret_cast<const float*>(bytes_ + i * stride_); }
  /** The cloud index of input point j; -1 if it lies outside the cloud or is not finite. */
  std::int64_t source(std::size_t j) const {
    const std::int64_t i = subset_ ? subset_[j] : std::int64_t(j);
    return (i >= 0 && std::size_t(i) < count_ && finite3(point(std::size_t(i)))) ? i : -1;
  }

 private:
  const char* bytes_;
  std::size_t count_, stride_;
  const std::int32_t* subset_;
  std::size_t size_;
};

/** Where the finite points lie: their bounding box, a sample and their bulk (see bulkBox) once needed. */
struct PointIndex::Extent {
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  std::size_t finite = 0;
  std::vector<std::array<float, 3>> sample;  // an even sample of the points, once taken
  bool has_bulk = false;
  double bulk_lo[3] = {0, 0, 0}, bulk_hi[3] = {0, 0, 0};

  explicit Extent(const Input& in) {
    for (std::size_t j = 0; j < in.size(); ++j) {
      const std::int64_t i = in.source(j);
      if (i < 0) continue;
      ++finite;
      const float* p = in.point(std::size_t(i));
      for (int a = 0; a < 3; ++a)
        lo[a] = std::min(lo[a], double(p[a])), hi[a] = std::max(hi[a], double(p[a]));
    }
  }

  void takeSample(const Input& in) {
    if (!sample.empty()) return;
    const std::size_t n = in.size(), m = std::min(n, detail::kCellSizeSample);
    sample.reserve(m);
    for (std::size_t s = 0; s < m; ++s) {
      const std::int64_t i = in.source(s * n / m);
      if (i < 0) continue;
      const float* p = in.point(std::size_t(i));
      sample.push_back({p[0], p[1], p[2]});
    }
  }

  void findBulk(const Input& in) {
    if (has_bulk) return;
    takeSample(in);
    detail::bulkBox(sample, lo, hi, bulk_lo, bulk_hi);
    has_bulk = true;
  }
};

/** The points the tree holds, by cell key, and the outliers: finite points beyond the key range. */
struct PointIndex::Placement {
  std::vector<Key> keys;
  std::vector<std::int32_t> ids, outliers;
};

void PointIndex::build(const float* xyz, std::size_t count, std::size_t stride_bytes,
                       const std::int32_t* subset, std::size_t subset_size) {
  const Input in(xyz, count, stride_bytes, subset, subset_size);
  Extent extent(in);
  if (extent.finite > 0 && automatic_) {
    extent.takeSample(in);
    resolution_ = detail::chooseCellSize(extent.sample, extent.finite, extent.lo, extent.hi);
  }
  Placement placed;
  placePoints(in, extent, placed);
  // A sample sees few of the sparse cells, so where occupancy varies (a LiDAR's returns: dense near, sparse
  // far) the edge it gives can be several times too fine. The tree counts its cells exactly: then it gives
  // the edge, and the points go in again.
  if (automatic_ &&
      double(placed.keys.size()) < 0.5 * detail::kPointsPerCell * double(tree_.getOccupiedCount())) {
    resolution_ = detail::coarserCellSize(tree_, placed.keys.size());
    placePoints(in, extent, placed);
  }
  std::vector<std::int32_t>& ids = placed.ids;
  ids.insert(ids.end(), placed.outliers.begin(), placed.outliers.end());
  detail::RankedTable table;
  table.build(tree_, placed.keys, ids, in.data(), in.stride());
  any_ = table.size() > 0 ? table.index(0) : -1;
  storage_ = std::move(table);
  changed();
}

void PointIndex::changed() {
  if (auto* buckets = std::get_if<detail::CellBuckets>(&storage_)) buckets->settle();
  build_id_ = next_build_id++;
}

void PointIndex::makeUpdatable(std::int32_t offset, const std::int32_t* renumber) {
  const auto* table = std::get_if<detail::RankedTable>(&storage_);
  if (!table) return;
  detail::CellBuckets buckets;
  const auto fill = [&](const Key& cell, std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t i = begin; i < end; ++i) {
      const std::int32_t index = table->index(i);
      buckets.add(cell, table->points() + 3 * std::size_t(i), renumber ? renumber[index] : index + offset);
    }
  };
  table->forEachRun(tree_, fill);
  if (table->size() > 0) fill(kOutliers, table->begin(table->outlierRun()), table->end(table->outlierRun()));
  buckets.settle();
  any_ = table->size() == 0 ? -1 : renumber ? renumber[table->index(0)] : table->index(0) + offset;
  storage_ = std::move(buckets);
}

std::size_t PointIndex::add(const float* xyz, std::size_t count, std::size_t stride_bytes,
                            std::int32_t first_index) {
  if (first_index < 0) throw std::invalid_argument("pcl::fot::PointIndex::add: a negative first index");
  const char* bytes = reinterpret_cast<const char*>(xyz);
  std::vector<std::int32_t> indices(count, -1);
  for (std::size_t i = 0; i < count; ++i) {
    if (!finite3(reinterpret_cast<const float*>(bytes + i * stride_bytes))) continue;
    if (std::uint64_t(first_index) + i > std::uint64_t(std::numeric_limits<std::int32_t>::max()))
      throw std::invalid_argument("pcl::fot::PointIndex::add: an index past INT32_MAX");
    indices[i] = std::int32_t(first_index + std::int64_t(i));
  }
  return add(xyz, count, stride_bytes, indices.data());
}

std::size_t PointIndex::add(const float* xyz, std::size_t count, std::size_t stride_bytes,
                            const std::int32_t* indices) {
  const char* bytes = reinterpret_cast<const char*>(xyz);
  const auto point = [&](std::size_t i) { return reinterpret_cast<const float*>(bytes + i * stride_bytes); };
  const auto taken = [&](std::size_t i) { return indices[i] >= 0 && finite3(point(i)); };
  makeUpdatable(0);
  // The checks come first, so that a bad index adds none: none held already, none given twice. Indices in
  // increasing order, as FastOctTreeSearch and the overload above give them, are distinct as they are.
  std::size_t taking = 0, finite = 0;
  std::int32_t first_taken = -1, last = -1;
  bool increasing = true;
  for (std::size_t i = 0; i < count; ++i) {
    if (!finite3(point(i))) continue;
    ++finite;
    if (indices[i] < 0) continue;
    if (buckets().contains(indices[i]))
      throw std::invalid_argument("pcl::fot::PointIndex::add: index " + std::to_string(indices[i]) +
                                  " is held already");
    if (taking++ == 0) first_taken = indices[i];
    increasing = increasing && indices[i] > last;
    last = indices[i];
  }
  if (!increasing) {
    std::vector<std::int32_t> sorted;
    sorted.reserve(taking);
    for (std::size_t i = 0; i < count; ++i)
      if (taken(i)) sorted.push_back(indices[i]);
    std::sort(sorted.begin(), sorted.end());
    const auto twice = std::adjacent_find(sorted.begin(), sorted.end());
    if (twice != sorted.end())
      throw std::invalid_argument("pcl::fot::PointIndex::add: index " + std::to_string(*twice) +
                                  " is given twice");
  }
  if (taking == 0) return 0;
  if (size() == 0) {  // nothing to keep: the grid fits itself to these points
    if (taking == finite) {
      build(xyz, count, stride_bytes);
    } else {
      std::vector<std::int32_t> subset;
      subset.reserve(taking);
      for (std::size_t i = 0; i < count; ++i)
        if (taken(i)) subset.push_back(std::int32_t(i));
      build(xyz, count, stride_bytes, subset.data(), subset.size());
    }
    makeUpdatable(0, indices);  // build numbered the points by their place in the batch
    return size();
  }
  const std::size_t before = size();
  Accessor writer(tree_);
  const CellGrid& grid = tree_.getGrid();
  for (std::size_t i = 0; i < count; ++i) {
    if (!taken(i)) continue;
    const float* p = point(i);
    Key key;
    if (!grid.pointToKey(p[0], p[1], p[2], key)) {
      buckets().add(kOutliers, p, indices[i]);
    } else if (buckets().add(key, p, indices[i])) {
      writer.setValidCell(key, CellState::Occupied);
    }
  }
  if (any_ < 0) any_ = first_taken;
  const std::size_t added = size() - before;
  refitGrid();
  changed();
  return added;
}

void PointIndex::refitGrid() {
  // A map that grows in place crowds its cells (frames of a moving sensor overlap), or thins out as it
  // forgets. An automatic index then picks its edge anew, as a hash table grows: rarely, so it costs O(1)
  // a point in the long run.
  constexpr double kSlack = 4.0;
  const double per_cell = double(size()) / double(std::max<std::uint64_t>(1, tree_.getOccupiedCount()));
  if (!automatic_ || size() < 1024 ||
      (per_cell <= kSlack * detail::kPointsPerCell && per_cell >= detail::kPointsPerCell / kSlack))
    return;
  std::vector<float> xyz;
  std::vector<std::int32_t> ids;
  xyz.reserve(3 * size());
  ids.reserve(size());
  buckets().forEachPoint([&](const detail::BucketPoint& p) {
    xyz.insert(xyz.end(), p.p, p.p + 3);
    ids.push_back(p.index);
  });
  build(xyz.data(), ids.size(), 3 * sizeof(float));
  makeUpdatable(0, ids.data());
}

std::size_t PointIndex::remove(const std::int32_t* indices, std::size_t count,
                               std::vector<std::int32_t>* removed_indices) {
  makeUpdatable(0);
  Accessor writer(tree_);
  std::size_t removed = 0;
  for (std::size_t i = 0; i < count; ++i) {
    Key cell;
    bool emptied;
    if (!buckets().remove(indices[i], cell, emptied)) continue;
    ++removed;
    if (removed_indices) removed_indices->push_back(indices[i]);
    if (emptied && cell != kOutliers) writer.setValidCell(cell, CellState::Unknown);
  }
  if (removed > 0) {
    refitGrid();
    if (!buckets().contains(any_)) {
      any_ = -1;
      buckets().forEachPoint([&](const detail::BucketPoint& p) { any_ = p.index; });
    }
    changed();
  }
  return removed;
}

std::size_t PointIndex::removeBox(const float lo[3], const float hi[3], bool inside,
                                  std::vector<std::int32_t>* removed) {
  makeUpdatable(0);
  // Keys grow with coordinates, so a cell whose key lies strictly between the keys of lo and hi on every
  // axis holds only points inside the box, and one beyond them on some axis only points outside it: only
  // the cells on the box's faces are read point by point, and the walk skips the subtrees it keeps whole.
  // A removal costs the cells it removes and those on the faces, not every point held.
  const CellGrid& grid = tree_.getGrid();
  std::int64_t klo[3], khi[3];
  for (unsigned a = 0; a < 3; ++a) {
    klo[a] = stretchedKey(grid, lo[a], a);
    khi[a] = stretchedKey(grid, hi[a], a);
  }
  std::vector<std::int32_t> doomed;
  const auto take = [&](const Key& cell) {
    std::uint32_t count = 0;
    const detail::PointBox* boxes;
    const detail::BucketPoint* points = buckets().find(cell, count, boxes);
    if (count == 0) return;
    const std::int64_t k[3] = {cell.x, cell.y, cell.z};
    bool within = false, beyond = false;  // the outliers have no cell: each point is read
    if (cell != kOutliers) {
      within = true;
      for (unsigned a = 0; a < 3; ++a) {
        within = within && k[a] > klo[a] && k[a] < khi[a];
        beyond = beyond || k[a] < klo[a] || k[a] > khi[a];
      }
    }
    for (std::uint32_t i = 0; i < count; ++i) {
      if (points[i].index < 0) continue;  // a hole
      const float* p = points[i].p;
      const bool in = within || (!beyond && p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] &&
                                 p[1] <= hi[1] && p[2] >= lo[2] && p[2] <= hi[2]);
      if (in == inside) doomed.push_back(points[i].index);
    }
  };
  const auto takeRegion = [&](const Region& r) {
    const std::int32_t side = std::int32_t(1) << r.level;
    for (std::int32_t x = 0; x < side; ++x)
      for (std::int32_t y = 0; y < side; ++y)
        for (std::int32_t z = 0; z < side; ++z) take(Key{r.min_key.x + x, r.min_key.y + y, r.min_key.z + z});
  };
  // The stretched keys, one past the range at most, fit a Key.
  const Key box_lo{std::int32_t(klo[0]), std::int32_t(klo[1]), std::int32_t(klo[2])};
  const Key box_hi{std::int32_t(khi[0]), std::int32_t(khi[1]), std::int32_t(khi[2])};
  const auto occupied = [&](const Region& r) {
    if (r.state == CellState::Occupied) takeRegion(r);
  };
  if (inside) {
    tree_.forEachRegionInBox(box_lo, box_hi, occupied);  // the cells the box touches
  } else {  // all but the cells strictly between the keys of lo and hi
    tree_.forEachRegionOutsideBox(Key{box_lo.x + 1, box_lo.y + 1, box_lo.z + 1},
                                  Key{box_hi.x - 1, box_hi.y - 1, box_hi.z - 1}, occupied);
  }
  take(kOutliers);
  return remove(doomed.data(), doomed.size(), removed);
}

void PointIndex::placePoints(const Input& in, Extent& extent, Placement& placed) {
  double origin[3] = {0, 0, 0};
  if (extent.finite > 0) {
    // The grid is centred on the points, or on their bulk when they reach further than its keys: then a
    // few stray points far away become the outliers, rather than the bulk. The centre sits kCentreKey cells
    // from key 0, away from the planes where the nodes of levels 1 to 16 all meet (see tree_coord), so that
    // the searches seldom climb that high.
    const double reach = 2.0 * double(kMaxKey - kCentreKey) * resolution_;
    const bool fits = extent.hi[0] - extent.lo[0] <= reach && extent.hi[1] - extent.lo[1] <= reach &&
                      extent.hi[2] - extent.lo[2] <= reach;
    if (!fits) extent.findBulk(in);
    for (int a = 0; a < 3; ++a) {
      const double centre =
          0.5 * (fits ? extent.lo[a] + extent.hi[a] : extent.bulk_lo[a] + extent.bulk_hi[a]);
      origin[a] = (std::floor(centre / resolution_) - double(kCentreKey)) * resolution_;
    }
  }
  // Points near float's limits may put a centred grid beyond them: then it is centred on 0, and the
  // points beyond its key range are outliers.
  if (!CellGrid::whyInvalid(resolution_, origin[0], origin[1], origin[2]).empty())
    std::fill(origin, origin + 3, 0.0);
  tree_ = FastOctTree(CellGrid(resolution_, origin[0], origin[1], origin[2]));
  placed.keys.clear();
  placed.ids.clear();
  placed.outliers.clear();
  placed.keys.reserve(in.size());
  placed.ids.reserve(in.size());
  Accessor writer(tree_);
  for (std::size_t j = 0; j < in.size(); ++j) {
    const std::int64_t i = in.source(j);
    if (i < 0) continue;
    const float* p = in.point(std::size_t(i));
    Key key;
    if (!tree_.getGrid().pointToKey(p[0], p[1], p[2], key)) {
      placed.outliers.push_back(std::int32_t(i));
      continue;
    }
    writer.setValidCell(key, CellState::Occupied);
    placed.keys.push_back(key);
    placed.ids.push_back(std::int32_t(i));
  }
}

std::size_t PointIndex::search(const float q[3], std::size_t k, double bound, Metric metric,
                               std::vector<std::int32_t>& indices, std::vector<float>& distances) const {
  indices.clear();
  distances.clear();
  if (!finite3(q) || k == 0 || bound < 0 || size() == 0) return 0;

  // This thread's path from its previous query on this build, so queries in spatial order start near.
  thread_local const PointIndex* owner = nullptr;
  thread_local std::uint64_t owner_build = 0;
  thread_local std::optional<ConstAccessor> accessor;
  const bool accessor_fresh = owner != this || owner_build != build_id_ || !accessor;
  if (accessor_fresh) {
    accessor.emplace(tree_);
    owner = this;
    owner_build = build_id_;
  }

  // The walk starts in the query's cell; any nearby cell would give the same, exact, answer, so the cell
  // comes from the reciprocal, clamped for far queries, rather than from pointToKey's exact division. The
  // boxes' gaps allow for the difference (PointPolicy's slack).
  const CellGrid& grid = tree_.getGrid();
  const double inverse = 1.0 / grid.resolution();
  double qc[3];
  std::int32_t cell[3];
  for (int a = 0; a < 3; ++a) {
    qc[a] = (double(q[a]) - grid.origin()[a]) * inverse;
    cell[a] = std::int32_t(std::clamp(std::floor(qc[a]), double(kMinKey), double(kMaxKey)));
  }
  const Key key{cell[0], cell[1], cell[2]};
  thread_local std::vector<detail::PointHit> results;
  thread_local std::uint32_t last_slot = kNoSlot;  // this thread's previous nearest point on this build
  if (accessor_fresh) last_slot = kNoSlot;
  results.clear();
  const std::size_t keep = k >= size() ? detail::kAllPoints : k;  // all of them: no insertion in order needed
  std::visit(
      [&](const auto& storage) {
        using Storage = std::decay_t<decltype(storage)>;
        detail::PointPolicy<Storage> policy(storage, grid.resolution(), q, qc, metric, keep, bound, results);
        // Queries in spatial order have nearby answers: the previous one bounds the walk from the start.
        // Offering a point twice is harmless for one neighbour (the repeat does not beat itself).
        if constexpr (std::is_same_v<Storage, detail::CellBuckets>) {
          if (keep == 1 && storage.contains(std::int32_t(last_slot))) {
            const detail::BucketPoint& p = storage.point(std::int32_t(last_slot));
            policy.offer(p.p, p.index, last_slot);
          }
          // Most queries fall among the points: their own cell, found by its key, often holds the whole
          // answer, and then the walk is not needed. The cell's box proves it (PointPolicy::settled).
          if (!policy.visitOwnCell(key) && tree_.getOccupiedCount() > 0)
            detail::NeighbourWalk<detail::PointPolicy<Storage>>(tree_, CellState::Occupied, nullptr, policy)
                .run(*accessor, key);
          policy.visitBucket(kOutliers);
        } else {
          if (keep == 1 && last_slot != kNoSlot)
            policy.offer(storage.points() + 3 * std::size_t(last_slot), storage.index(last_slot), last_slot);
          const std::uint64_t outliers = storage.outlierRun();
          if (storage.begin(outliers) > 0)
            detail::NeighbourWalk<detail::PointPolicy<Storage>>(tree_, CellState::Occupied, storage.ranks(),
                                                                policy)
                .run(*accessor, key);
          if (storage.end(outliers) > storage.begin(outliers)) policy.visitCell(TreeCoord(), outliers);
        }
      },
      storage_);

  if (keep == detail::kAllPoints || keep > detail::kLargeK) std::sort(results.begin(), results.end());
  if (k == 1 && !results.empty()) last_slot = results.front().slot;
  indices.reserve(results.size());
  distances.reserve(results.size());
  for (const detail::PointHit& h : results) {
    indices.push_back(h.index);
    distances.push_back(h.distance);
  }
  return results.size();
}

std::size_t PointIndex::nearestK(const float q[3], std::size_t k, Metric metric,
                                 std::vector<std::int32_t>& indices, std::vector<float>& distances) const {
  return search(q, k, std::numeric_limits<double>::infinity(), metric, indices, distances);
}

std::size_t PointIndex::radiusSearch(const float q[3], double radius, Metric metric,
                                     std::vector<std::int32_t>& indices, std::vector<float>& distances,
                                     std::size_t max_results) const {
  if (!(radius >= 0)) {
    indices.clear();
    distances.clear();
    return 0;
  }
  const double limit = metric != Metric::Manhattan ? radius * radius : radius;
  return search(q, max_results ? max_results : detail::kAllPoints, limit, metric, indices, distances);
}

std::size_t PointIndex::getMemoryBytes() const {
  return sizeof(*this) + tree_.getMemoryBytes() +
         std::visit([](const auto& storage) { return storage.memoryBytes(); }, storage_);
}

}  // namespace fot
}  // namespace pcl
