#include <pcl_fot/nearest_neighbor.h>

#include <algorithm>
#include <stdexcept>

namespace pcl {
namespace fot {

/** Distances in cells between a query cell and cells or cubes, in tree coordinates. */
class NearestCellSearch::Policy {
 public:
  using Distance = std::int64_t;

  Policy(Metric metric, const Key& query, std::size_t k, std::int64_t limit, std::vector<Candidate>& heap)
      : metric_(metric),
        q_{tree_coord::fromKey(query.x), tree_coord::fromKey(query.y), tree_coord::fromKey(query.z)},
        k_(k),
        limit_(limit),
        heap_(heap) {}

  void childGaps(const std::uint32_t lo[3], unsigned child_level, Distance gap[3][2]) const {
    const std::int64_t half = std::int64_t(1) << child_level;
    for (int a = 0; a < 3; ++a)
      for (int h = 0; h < 2; ++h) {
        const std::int64_t first = std::int64_t(lo[a]) + h * half, last = first + half - 1;
        // Capped: no two valid keys are farther apart, and a smaller lower bound stays a lower bound.
        const std::int64_t d = std::min<std::int64_t>(std::max<std::int64_t>({first - q_[a], q_[a] - last, 0}), kMaxGap);
        gap[a][h] = metric_ == Metric::Manhattan ? d : d * d;
      }
  }

  Distance exterior(const std::uint32_t lo[3], unsigned level) const {
    const std::int64_t side = std::int64_t(1) << level;
    std::int64_t nearest = kMaxGap;
    for (int a = 0; a < 3; ++a)
      nearest = std::min({nearest, std::int64_t(q_[a]) - lo[a] + 1, std::int64_t(lo[a]) + side - q_[a]});
    return metric_ == Metric::Manhattan ? nearest : nearest * nearest;
  }

  bool worthVisiting(Distance lower_bound) const { return lower_bound <= bound(); }
  bool settled(Distance exterior) const { return bound() < exterior; }
  bool wholeRegions() const { return k_ == 1; }

  /** For one nearest cell, a cube's best cell is the query clamped into it. */
  void visitRegion(const std::uint32_t lo[3], unsigned level, std::uint64_t) {
    const std::uint32_t last = std::uint32_t((std::uint64_t(1) << level) - 1);
    const std::uint32_t cell[3] = {std::clamp(q_[0], lo[0], lo[0] + last), std::clamp(q_[1], lo[1], lo[1] + last),
                                   std::clamp(q_[2], lo[2], lo[2] + last)};
    visitCell(cell, 0);
  }

  void visitCell(const std::uint32_t cell[3], std::uint64_t) {
    std::int64_t d[3];
    for (int a = 0; a < 3; ++a) d[a] = std::abs(std::int64_t(cell[a]) - q_[a]);
    const Candidate c{combine(d), {cell[0], cell[1], cell[2]}};
    if (c.distance > bound()) return;
    if (heap_.size() < k_) {
      heap_.push_back(c);
      std::push_heap(heap_.begin(), heap_.end());
    } else if (c < heap_.front()) {
      std::pop_heap(heap_.begin(), heap_.end());
      heap_.back() = c;
      std::push_heap(heap_.begin(), heap_.end());
    }
  }

 private:
  static constexpr std::int64_t kMaxGap = (std::int64_t(1) << 30) + 1;

  Distance combine(const std::int64_t d[3]) const {
    return metric_ == Metric::Manhattan ? d[0] + d[1] + d[2] : d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  }
  /** The distance a new cell must not exceed: the k-th best so far, else the limit. */
  Distance bound() const { return heap_.size() < k_ ? limit_ : std::min(limit_, heap_.front().distance); }

  Metric metric_;
  std::uint32_t q_[3];
  std::size_t k_;
  std::int64_t limit_;
  std::vector<Candidate>& heap_;
};

NearestCellSearch::NearestCellSearch(const FastOctTree& tree, Metric metric, CellState target)
    : tree_(tree), metric_(metric), target_(target), accessor_(tree) {
  if (target == CellState::Unknown)
    throw std::invalid_argument("pcl::fot::NearestCellSearch: unknown cells are not searchable");
}

void NearestCellSearch::search(const Key& query, std::size_t k, std::int64_t bound) {
  if (!isValidKey(query)) throwKeyOutOfRange("pcl::fot::NearestCellSearch", query);
  heap_.clear();
  if (k == 0 || bound < 0) return;
  Policy policy(metric_, query, k, bound, heap_);
  detail::NeighbourWalk<Policy>(tree_, target_, nullptr, policy).run(accessor_, query);
  std::sort(heap_.begin(), heap_.end());
}

std::size_t NearestCellSearch::copyMatches(std::vector<CellMatch>& matches) const {
  matches.clear();
  for (const Candidate& c : heap_)
    matches.push_back(CellMatch{Key{tree_coord::toKey(c.u[0]), tree_coord::toKey(c.u[1]), tree_coord::toKey(c.u[2])},
                                c.distance});
  return matches.size();
}

bool NearestCellSearch::nearest(const Key& query, CellMatch& match, std::int64_t max_distance) {
  search(query, 1, max_distance);
  if (heap_.empty()) return false;
  const Candidate& c = heap_.front();
  match = CellMatch{Key{tree_coord::toKey(c.u[0]), tree_coord::toKey(c.u[1]), tree_coord::toKey(c.u[2])}, c.distance};
  return true;
}

std::size_t NearestCellSearch::nearestK(const Key& query, std::size_t k, std::vector<CellMatch>& matches,
                                        std::int64_t max_distance) {
  search(query, k, max_distance);
  return copyMatches(matches);
}

std::size_t NearestCellSearch::radius(const Key& query, std::int64_t radius, std::vector<CellMatch>& matches) {
  search(query, std::numeric_limits<std::size_t>::max(), radius);
  return copyMatches(matches);
}

}  // namespace fot
}  // namespace pcl
