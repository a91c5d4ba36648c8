#include <pcl_fot/point_index.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include <pcl_fot/accessor.h>

namespace pcl {
namespace fot {
namespace {

struct Hit {
  float distance;
  std::int32_t index;
  bool operator<(const Hit& o) const { return distance < o.distance || (distance == o.distance && index < o.index); }
};

bool finite3(const float* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

/** PCL's distances, to the bit: FLANN's L2_Simple and L1 sum the axes left to right in float. */
float pointDistance(Metric metric, const float* p, const float q[3]) {
  const float dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
  return metric == Metric::Euclidean ? dx * dx + dy * dy + dz * dz
                                     : std::fabs(dx) + std::fabs(dy) + std::fabs(dz);
}

/** The Morton number of a cell inside an aligned cube of 2^level cells, in the tree's octant order. */
std::uint64_t mortonWithin(std::uint32_t x, std::uint32_t y, std::uint32_t z, unsigned level) {
  std::uint64_t code = 0;
  for (unsigned b = 0; b < level; ++b)
    code |= (std::uint64_t((x >> b) & 1u) << (3 * b)) | (std::uint64_t((y >> b) & 1u) << (3 * b + 1)) |
            (std::uint64_t((z >> b) & 1u) << (3 * b + 2));
  return code;
}

/** Numbers the occupied cells in Morton order: each bitmap word gets the rank of its first one. */
std::uint64_t assignRanks(const FastOctTree& tree, NodeWord w, std::size_t offset, unsigned level,
                          std::uint64_t next, std::vector<std::uint64_t>& ranks) {
  if (node::isBitmap(w)) {
    ranks[offset] = next;
    return next + (std::uint64_t(node::popcount(node::octantMask(w, CellState::Occupied))) << (3 * (level - 1)));
  }
  const std::size_t first = node::childBase(w);
  for (unsigned o = 0; o < 8; ++o) next = assignRanks(tree, tree.words()[first + o], first + o, level - 1, next, ranks);
  return next;
}

std::atomic<std::uint64_t> next_build_id{1};

}  // namespace

/** Distances from one query point, in metres, to the points of the cells the walk visits. */
class PointIndex::Policy {
 public:
  using Distance = double;

  Policy(const PointIndex& index, const float q[3], Metric metric, std::size_t k, double limit, std::vector<Hit>& heap)
      : index_(index), grid_(index.tree_.getGrid()), q_{q[0], q[1], q[2]}, metric_(metric), k_(k), limit_(limit),
        heap_(heap) {}

  // Bounds are shaded down a little: a float distance may come out up to a few ulps below the exact one.
  Distance lowerBound(const std::uint32_t lo[3], unsigned level) const {
    double gap[3];
    for (int a = 0; a < 3; ++a) {
      double box_lo, box_hi;
      box(lo[a], level, a, box_lo, box_hi);
      gap[a] = std::max({box_lo - q_[a], q_[a] - box_hi, 0.0});
    }
    return shade(combine(gap));
  }

  Distance exterior(const std::uint32_t lo[3], unsigned level) const {
    double nearest = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
      double box_lo, box_hi;
      box(lo[a], level, a, box_lo, box_hi);
      nearest = std::min({nearest, q_[a] - box_lo, box_hi - q_[a]});
    }
    nearest = std::max(nearest, 0.0);
    return shade(metric_ == Metric::Euclidean ? nearest * nearest : nearest);
  }

  bool worthVisiting(Distance lower_bound) const { return lower_bound <= bound(); }
  bool settled(Distance exterior) const { return bound() < exterior; }
  bool wholeRegions() const { return false; }
  void visitRegion(const std::uint32_t[3], unsigned, std::uint64_t) {}

  void visitCell(const std::uint32_t[3], std::uint64_t rank) {
    const std::uint32_t end = index_.start_[rank + 1];
    for (std::uint32_t i = index_.start_[rank]; i < end; ++i) offer(&index_.xyz_[3 * std::size_t(i)], index_.index_[i]);
  }

  void offer(const float* p, std::int32_t index) {
    const Hit h{pointDistance(metric_, p, q_), index};
    if (double(h.distance) > bound()) return;
    if (heap_.size() < k_) {
      heap_.push_back(h);
      std::push_heap(heap_.begin(), heap_.end());
    } else if (h < heap_.front()) {
      std::pop_heap(heap_.begin(), heap_.end());
      heap_.back() = h;
      std::push_heap(heap_.begin(), heap_.end());
    }
  }

 private:
  /** The extent in metres of a cube's side along one axis. */
  void box(std::uint32_t lo, unsigned level, int axis, double& box_lo, double& box_hi) const {
    box_lo = grid_.origin()[axis] + double(tree_coord::toKey(lo)) * grid_.resolution();
    box_hi = box_lo + std::ldexp(grid_.resolution(), int(level));
  }
  double combine(const double g[3]) const {
    return metric_ == Metric::Euclidean ? g[0] * g[0] + g[1] * g[1] + g[2] * g[2] : g[0] + g[1] + g[2];
  }
  static double shade(double d) { return d * (1.0 - 4e-6); }
  double bound() const { return heap_.size() < k_ ? limit_ : std::min(limit_, double(heap_.front().distance)); }

  const PointIndex& index_;
  const VoxelGrid& grid_;
  float q_[3];
  Metric metric_;
  std::size_t k_;
  double limit_;
  std::vector<Hit>& heap_;
};

PointIndex::PointIndex(double resolution) : resolution_(resolution), tree_(resolution) {}

void PointIndex::build(const float* xyz, std::size_t count, std::size_t stride_bytes, const std::int32_t* subset,
                       std::size_t subset_size) {
  const char* bytes = reinterpret_cast<const char*>(xyz);
  auto point = [&](std::size_t i) { return reinterpret_cast<const float*>(bytes + i * stride_bytes); };
  const std::size_t n = subset ? subset_size : count;
  auto source = [&](std::size_t j) -> std::int64_t {
    const std::int64_t i = subset ? subset[j] : std::int64_t(j);
    return (i >= 0 && std::size_t(i) < count && finite3(point(std::size_t(i)))) ? i : -1;
  };

  // The grid is centred on the points, which keeps the key range around them.
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (std::size_t j = 0; j < n; ++j) {
    const std::int64_t i = source(j);
    if (i < 0) continue;
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], double(point(std::size_t(i))[a])), hi[a] = std::max(hi[a], double(point(std::size_t(i))[a]));
  }
  double origin[3] = {0, 0, 0};
  if (lo[0] <= hi[0])
    for (int a = 0; a < 3; ++a) origin[a] = std::floor(0.5 * (lo[a] + hi[a]) / resolution_) * resolution_;
  tree_ = FastOctTree(VoxelGrid(resolution_, origin[0], origin[1], origin[2]));
  build_id_ = next_build_id++;
  outliers_xyz_.clear();
  outliers_index_.clear();

  std::vector<Key> keys;
  std::vector<std::int32_t> ids;
  keys.reserve(n);
  ids.reserve(n);
  Accessor writer(tree_);
  for (std::size_t j = 0; j < n; ++j) {
    const std::int64_t i = source(j);
    if (i < 0) continue;
    const float* p = point(std::size_t(i));
    Key key;
    if (!tree_.getGrid().pointToKey(p[0], p[1], p[2], key)) {
      outliers_xyz_.insert(outliers_xyz_.end(), p, p + 3);
      outliers_index_.push_back(std::int32_t(i));
      continue;
    }
    writer.setValidCell(key, CellState::Occupied);
    keys.push_back(key);
    ids.push_back(std::int32_t(i));
  }

  ranks_.assign(tree_.poolWords(), 0);
  const std::uint64_t cells = assignRanks(tree_, tree_.rootWord(), 0, tree_.rootLevel(), 0, ranks_);

  // Each point's cell rank, then a counting sort into the table.
  std::vector<std::uint32_t> rank_of(keys.size());
  ConstAccessor reader(tree_);
  for (std::size_t j = 0; j < keys.size(); ++j) {
    const Key& k = keys[j];
    const unsigned level = reader.locatePath(k);
    const std::size_t offset = reader.pathOffset(level);
    const std::uint32_t u[3] = {tree_coord::fromKey(k.x), tree_coord::fromKey(k.y), tree_coord::fromKey(k.z)};
    const unsigned o = tree_coord::octant(u[0], u[1], u[2], level);
    const std::uint32_t before = node::octantMask(tree_.words()[offset], CellState::Occupied) & ((1u << o) - 1u);
    const std::uint32_t inner = std::uint32_t((std::uint64_t(1) << (level - 1)) - 1);
    rank_of[j] = std::uint32_t(ranks_[offset] + (std::uint64_t(node::popcount(before)) << (3 * (level - 1))) +
                               mortonWithin(u[0] & inner, u[1] & inner, u[2] & inner, level - 1));
  }
  start_.assign(std::size_t(cells) + 1, 0);
  for (std::uint32_t r : rank_of) ++start_[r + 1];
  for (std::size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
  xyz_.resize(3 * keys.size());
  index_.resize(keys.size());
  std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
  for (std::size_t j = 0; j < keys.size(); ++j) {
    const std::uint32_t at = fill[rank_of[j]]++;
    const float* p = point(std::size_t(ids[j]));
    std::copy(p, p + 3, &xyz_[3 * std::size_t(at)]);
    index_[at] = ids[j];
  }
  // Within a cell, points keep their input order: ties then resolve by index without extra work.
}

std::size_t PointIndex::search(const float q[3], std::size_t k, double bound, Metric metric,
                               std::vector<std::int32_t>& indices, std::vector<float>& distances) const {
  indices.clear();
  distances.clear();
  if (!finite3(q) || k == 0 || bound < 0 || (index_.empty() && outliers_index_.empty())) return 0;

  // This thread's path from its previous query on this build, so queries in spatial order start near.
  thread_local const PointIndex* owner = nullptr;
  thread_local std::uint64_t owner_build = 0;
  thread_local std::optional<ConstAccessor> accessor;
  if (owner != this || owner_build != build_id_ || !accessor) {
    accessor.emplace(tree_);
    owner = this;
    owner_build = build_id_;
  }

  thread_local std::vector<Hit> heap;
  heap.clear();
  Policy policy(*this, q, metric, k, bound, heap);
  const VoxelGrid& grid = tree_.getGrid();
  Key key;
  if (!grid.pointToKey(q[0], q[1], q[2], key)) {  // far away: start from the nearest representable cell
    std::int32_t* axes[3] = {&key.x, &key.y, &key.z};
    for (int a = 0; a < 3; ++a) {
      const double c = std::floor((double(q[a]) - grid.origin()[a]) / grid.resolution());
      *axes[a] = std::int32_t(std::clamp(c, double(kMinKey), double(kMaxKey)));
    }
  }
  if (!index_.empty()) detail::NeighbourWalk<Policy>(tree_, CellState::Occupied, ranks_.data(), policy).run(*accessor, key);
  for (std::size_t i = 0; i < outliers_index_.size(); ++i) policy.offer(&outliers_xyz_[3 * i], outliers_index_[i]);

  std::sort(heap.begin(), heap.end());
  indices.reserve(heap.size());
  distances.reserve(heap.size());
  for (const Hit& h : heap) {
    indices.push_back(h.index);
    distances.push_back(h.distance);
  }
  return heap.size();
}

std::size_t PointIndex::nearestK(const float q[3], std::size_t k, Metric metric, std::vector<std::int32_t>& indices,
                                 std::vector<float>& distances) const {
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
  const double limit = metric == Metric::Euclidean ? radius * radius : radius;
  return search(q, max_results ? max_results : std::numeric_limits<std::size_t>::max(), limit, metric, indices,
                distances);
}

std::size_t PointIndex::getMemoryBytes() const {
  return sizeof(*this) + tree_.getMemoryBytes() + ranks_.capacity() * sizeof(std::uint64_t) +
         start_.capacity() * sizeof(std::uint32_t) + xyz_.capacity() * sizeof(float) +
         index_.capacity() * sizeof(std::int32_t) + outliers_xyz_.capacity() * sizeof(float) +
         outliers_index_.capacity() * sizeof(std::int32_t);
}

}  // namespace fot
}  // namespace pcl
