#include <pcl_fot/search/nearest_cell_search.h>

#include <algorithm>
#include <stdexcept>

#include "search/neighbour_walk.h"

namespace pcl {
namespace fot {

/** Distances in cells between a query cell and cells or cubes, in tree coordinates. */
class NearestCellSearch::Measure {
 public:
  using Distance = std::int64_t;

  Measure(Metric metric, const Key& query) : metric_(metric), q_(query) {}

  void childGaps(const TreeCoord& lo, unsigned child_level, Distance gap[3][2]) const {
    const std::int64_t half = std::int64_t(1) << child_level;
    for (unsigned a = 0; a < 3; ++a) {
      // The query's offset from the corner; at most one of each half's two terms is positive.
      const std::int64_t r = std::int64_t(q_[a]) - lo[a];
      const std::int64_t lower = std::max<std::int64_t>(-r, 0) + std::max<std::int64_t>(r - half + 1, 0),
                         upper = std::max<std::int64_t>(half - r, 0) +
                                 std::max<std::int64_t>(r - 2 * half + 1, 0);
      if (metric_ == Metric::Manhattan) {
        gap[a][0] = lower, gap[a][1] = upper;
      } else {  // capped: no two valid keys are farther apart, and a smaller lower bound stays a lower bound
        const std::int64_t l = std::min(lower, kMaxGap), u = std::min(upper, kMaxGap);
        gap[a][0] = l * l, gap[a][1] = u * u;
      }
    }
  }

  Distance exterior(const TreeCoord& lo, unsigned level) const {
    const std::int64_t side = std::int64_t(1) << level;
    std::int64_t nearest = kMaxGap;
    for (unsigned a = 0; a < 3; ++a)
      nearest = std::min({nearest, std::int64_t(q_[a]) - lo[a] + 1, std::int64_t(lo[a]) + side - q_[a]});
    return metric_ == Metric::Manhattan ? nearest : nearest * nearest;
  }

  Candidate candidate(const TreeCoord& cell) const {
    std::int64_t d[3];
    for (unsigned a = 0; a < 3; ++a) d[a] = std::abs(std::int64_t(cell[a]) - q_[a]);
    return Candidate{
        metric_ == Metric::Manhattan ? d[0] + d[1] + d[2] : d[0] * d[0] + d[1] * d[1] + d[2] * d[2], cell};
  }

  /** A cube's nearest cell: the query clamped into it. */
  TreeCoord clampInto(const TreeCoord& lo, unsigned level) const {
    const std::uint32_t last = tree_coord::lowMask(level);
    return TreeCoord(std::clamp(q_[0], lo[0], lo[0] + last), std::clamp(q_[1], lo[1], lo[1] + last),
                     std::clamp(q_[2], lo[2], lo[2] + last));
  }

 protected:
  Metric metric() const { return metric_; }
  const TreeCoord& query() const { return q_; }

 private:
  static constexpr std::int64_t kMaxGap = (std::int64_t(1) << 30) + 1;

  Metric metric_;
  TreeCoord q_;
};

/**
 * The nearest cell: one candidate, cubes taken whole. With the tie rule, boxes that could hold a cell at
 * the best distance so far are still searched, for a smaller key; without it, only those that could beat it.
 */
class NearestCellSearch::NearestOne : public Measure {
 public:
  NearestOne(Metric metric, const Key& query, std::int64_t limit, bool tie_rule, Distance floor)
      : Measure(metric, query),
        limit_(limit),
        tie_slack_(tie_rule ? 1 : 0),
        floor_(floor),
        bound_(limit < kUnbounded ? limit + 1 : limit) {}

  bool worthVisiting(Distance lower_bound) const { return lower_bound < bound_; }
  /**
   * A box only as near as the best holds one cell that near, the query clamped into it: it can improve the
   * result only if that cell's key is smaller.
   */
  bool mayImprove(Distance lower_bound, const TreeCoord& lo, unsigned level, std::size_t) const {
    if (lower_bound + tie_slack_ < bound_ || !found_) return true;  // nearer, or no tie rule
    return Candidate{lower_bound, clampInto(lo, level)} < best_;
  }
  /**
   * Outside the cube, a cell as near as the best lies beyond one face, and one exactly as near as that
   * face's gap is the query moved straight through it: with the tie rule only those with a smaller key
   * keep the walk going.
   */
  bool settled(const TreeCoord& lo, unsigned level) const {
    if (!found_ || tie_slack_ == 0 || bound_ == 0) return bound_ <= exterior(lo, level);
    const std::int64_t side = std::int64_t(1) << level;
    for (unsigned a = 0; a < 3; ++a)
      for (const std::int64_t step :
           {std::int64_t(lo[a]) - 1 - query()[a], std::int64_t(lo[a]) + side - query()[a]}) {
        const Distance gap = metric() == Metric::Manhattan ? std::llabs(step) : step * step;
        if (gap > best_.distance) continue;
        if (gap < best_.distance) return false;
        Candidate beyond{gap, query()};
        beyond.cell[a] = std::uint32_t(std::int64_t(query()[a]) + step);
        if (beyond < best_) return false;
      }
    return true;
  }
  bool wholeRegions() const { return true; }
  void visitRegion(const TreeCoord& lo, unsigned level, std::uint64_t) { visitCell(clampInto(lo, level), 0); }
  void visitCell(const TreeCoord& cell, std::uint64_t) {
    const Candidate c = candidate(cell);
    if (c.distance <= limit_ && (!found_ || c < best_)) {
      best_ = c;
      found_ = true;
      bound_ = c.distance <= floor_ ? 0 : c.distance + tie_slack_;  // at the floor nothing can beat it
    }
  }

  bool found() const { return found_; }
  const Candidate& best() const { return best_; }

 private:
  std::int64_t limit_;
  Distance tie_slack_;
  Distance floor_;  // no cell lies nearer
  Distance bound_;  // a box is searched if its lower bound is below this
  bool found_ = false;
  Candidate best_{};
};

/** The k nearest cells, kept in a heap, cubes split down to cells. */
class NearestCellSearch::NearestK : public Measure {
 public:
  NearestK(Metric metric, const Key& query, std::size_t k, std::int64_t limit, std::vector<Candidate>& heap)
      : Measure(metric, query), k_(k), limit_(limit), heap_(heap) {}

  bool worthVisiting(Distance lower_bound) const { return lower_bound <= bound(); }
  bool mayImprove(Distance, const TreeCoord&, unsigned, std::size_t) const { return true; }
  bool settled(const TreeCoord& lo, unsigned level) const { return bound() < exterior(lo, level); }
  bool wholeRegions() const { return false; }
  void visitRegion(const TreeCoord&, unsigned, std::uint64_t) {}
  void visitCell(const TreeCoord& cell, std::uint64_t) {
    const Candidate c = candidate(cell);
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
  /** The distance a new cell must not exceed: the k-th best so far, else the limit. */
  Distance bound() const { return heap_.size() < k_ ? limit_ : std::min(limit_, heap_.front().distance); }

  std::size_t k_;
  std::int64_t limit_;
  std::vector<Candidate>& heap_;
};

NearestCellSearch::NearestCellSearch(const FastOctTree& tree, Metric metric, CellState target)
    : tree_(tree), metric_(metric), target_(target), accessor_(tree) {
  if (target == CellState::Unknown)
    throw std::invalid_argument("pcl::fot::NearestCellSearch: unknown cells are not searchable");
}

bool NearestCellSearch::nearest(const Key& query, CellMatch& match, std::int64_t max_distance) {
  return findNearest(query, match, max_distance, true, -1);
}

bool NearestCellSearch::anyNearest(const Key& query, CellMatch& match, std::int64_t max_distance,
                                   std::int64_t min_distance) {
  return findNearest(query, match, max_distance, false, min_distance);
}

bool NearestCellSearch::findNearest(const Key& query, CellMatch& match, std::int64_t max_distance,
                                    bool tie_rule, std::int64_t floor) {
  if (!isValidKey(query)) throwKeyOutOfRange("pcl::fot::NearestCellSearch", query);
  if (max_distance < 0) return false;
  if (accessor_.getCell(query) == target_) {  // nothing beats distance 0
    match = CellMatch{query, 0};
    return true;
  }
  NearestOne policy(metric_, query, max_distance, tie_rule, floor);
  // Queries in spatial order have nearby answers: the previous one bounds the walk from the start.
  if (has_previous_ && accessor_.getCell(previous_) == target_) policy.visitCell(TreeCoord(previous_), 0);
  detail::NeighbourWalk<NearestOne>(tree_, target_, nullptr, policy).run(accessor_, query);
  if (!policy.found()) return false;
  const Candidate& c = policy.best();
  match = CellMatch{c.cell.key(), c.distance};
  previous_ = match.key;
  has_previous_ = true;
  return true;
}

void NearestCellSearch::search(const Key& query, std::size_t k, std::int64_t bound) {
  if (!isValidKey(query)) throwKeyOutOfRange("pcl::fot::NearestCellSearch", query);
  heap_.clear();
  if (k == 0 || bound < 0) return;
  NearestK policy(metric_, query, k, bound, heap_);
  detail::NeighbourWalk<NearestK>(tree_, target_, nullptr, policy).run(accessor_, query);
  std::sort(heap_.begin(), heap_.end());
}

std::size_t NearestCellSearch::copyMatches(std::vector<CellMatch>& matches) const {
  matches.clear();
  for (const Candidate& c : heap_) matches.push_back(CellMatch{c.cell.key(), c.distance});
  return matches.size();
}

std::size_t NearestCellSearch::nearestK(const Key& query, std::size_t k, std::vector<CellMatch>& matches,
                                        std::int64_t max_distance) {
  search(query, k, max_distance);
  return copyMatches(matches);
}

std::size_t NearestCellSearch::radius(const Key& query, std::int64_t radius,
                                      std::vector<CellMatch>& matches) {
  search(query, std::numeric_limits<std::size_t>::max(), radius);
  return copyMatches(matches);
}

}  // namespace fot
}  // namespace pcl
