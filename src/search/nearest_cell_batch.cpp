// NearestCellSearch's batch query: bricks of queries settled by bit dilation, the rest searched one by one,
// over threads.
#include <pcl_fot/search/nearest_cell_search.h>

#include <algorithm>
#include <array>
#include <optional>

#include <pcl_fot/detail/bits.h>
#include <pcl_fot/detail/worker_threads.h>

#include "search/brick_distance.h"

namespace pcl {
namespace fot {
namespace {

constexpr std::uint32_t kBrickMask = ~((std::uint32_t(1) << detail::kBrickLevel) - 1);
constexpr std::uint32_t kCellMask = ~kBrickMask;

struct Query {
  TreeCoord u;
  std::uint32_t index;
};

/** Morton order of the queries' bricks, z the most significant axis, as the tree lists its cells. */
bool brickBefore(const Query& a, const Query& b) {
  const std::uint32_t d[3] = {(a.u[0] ^ b.u[0]) & kBrickMask, (a.u[1] ^ b.u[1]) & kBrickMask,
                              (a.u[2] ^ b.u[2]) & kBrickMask};
  const auto lowerTopBit = [](std::uint32_t p, std::uint32_t q) { return p < q && p < (p ^ q); };
  unsigned axis = 2;
  for (unsigned a2 : {1u, 0u})
    if (lowerTopBit(d[axis], d[a2])) axis = a2;
  return (a.u[axis] & kBrickMask) < (b.u[axis] & kBrickMask);
}

bool sameBrick(const Query& a, const Query& b) {
  return ((a.u[0] ^ b.u[0]) | (a.u[1] ^ b.u[1]) | (a.u[2] ^ b.u[2])) <= kCellMask;
}

/** A cell's bit in its brick. */
unsigned cellBit(const Query& q) {
  constexpr unsigned side = detail::Brick::kSide;
  return (q.u[0] & kCellMask) + side * ((q.u[1] & kCellMask) + side * (q.u[2] & kCellMask));
}

/**
 * Answers the queries of whole bricks, order [first, last), into matches; returns how many were found. In
 * the Manhattan metric a brick of enough queries is settled by windows; `single` searches the rest.
 */
std::size_t answerBricks(NearestCellSearch& single, const Query* first, const Query* last,
                         const std::vector<Key>& queries, std::vector<CellMatch>& matches,
                         std::int64_t max_distance) {
  const bool dilate = single.metric() == Metric::Manhattan;
  std::optional<detail::BrickSettler> windows;  // built on the first brick dense enough for them
  constexpr std::uint8_t kUnsettled = 0xFF;
  std::array<std::uint8_t, detail::Brick::kWords * 64> distance;
  distance.fill(kUnsettled);
  std::size_t found = 0;
  for (const Query* end; first != last; first = end) {
    detail::Brick cells;
    for (end = first; end != last && sameBrick(*first, *end); ++end) {
      const unsigned bit = cellBit(*end);
      cells.bits[bit >> 6] |= std::uint64_t(1) << (bit & 63);
    }
    const TreeCoord corner = first->u.corner(detail::kBrickLevel);
    std::int64_t settled = -1;
    if (dilate && cells.count() >= detail::BrickSettler::kMinNearCells) {
      if (!windows) windows.emplace(single.tree(), single.target());
      settled =
          windows->settle(corner.u, cells, max_distance, [&](unsigned d, unsigned w, std::uint64_t bits) {
            for (; bits; bits &= bits - 1) distance[w * 64 + detail::lowestBit(bits)] = std::uint8_t(d);
          });
    }
    for (const Query* q = first; q != end; ++q) {
      const unsigned bit = cellBit(*q);
      CellMatch& m = matches[q->index];
      if (distance[bit] != kUnsettled) {
        TreeCoord u;
        windows->nearestAt(q->u[0] & kCellMask, q->u[1] & kCellMask, q->u[2] & kCellMask, distance[bit], u.u);
        m = CellMatch{u.key(), distance[bit]};
        ++found;
      } else if (max_distance > settled) {  // not settled by a window: further than it reaches
        found += single.nearest(queries[q->index], m, max_distance);
      }
    }
    for (const Query* q = first; q != end; ++q) distance[cellBit(*q)] = kUnsettled;
  }
  return found;
}

}  // namespace

std::size_t NearestCellSearch::nearest(const std::vector<Key>& queries, std::vector<CellMatch>& matches,
                                       std::int64_t max_distance) {
  for (const Key& q : queries)
    if (!isValidKey(q)) throwKeyOutOfRange("pcl::fot::NearestCellSearch", q);
  matches.assign(queries.size(), CellMatch{Key{0, 0, 0}, -1});
  std::vector<Query> order(queries.size());
  for (std::size_t i = 0; i < queries.size(); ++i) order[i] = Query{TreeCoord(queries[i]), std::uint32_t(i)};
  if (!std::is_sorted(order.begin(), order.end(), brickBefore))
    std::sort(order.begin(), order.end(), brickBefore);

  // Threads take contiguous runs of whole bricks, each with its own searcher.
  constexpr std::size_t kMinQueriesPerThread = 4096;
  const std::size_t n = order.size();
  const std::size_t workers = detail::workerCount(threads_, n / kMinQueriesPerThread);
  if (workers == 1)
    return answerBricks(*this, order.data(), order.data() + n, queries, matches, max_distance);
  std::vector<std::size_t> bounds(workers + 1, n), found(workers, 0);
  bounds[0] = 0;
  for (std::size_t w = 1; w < workers; ++w) {
    std::size_t b = std::max(bounds[w - 1], n * w / workers);
    while (b > 0 && b < n && sameBrick(order[b - 1], order[b])) ++b;
    bounds[w] = b;
  }
  detail::runWorkers(workers, [&](std::size_t w) {
    NearestCellSearch own(tree_, metric_, target_);
    found[w] = answerBricks(own, order.data() + bounds[w], order.data() + bounds[w + 1], queries, matches,
                            max_distance);
  });
  std::size_t total = 0;
  for (std::size_t f : found) total += f;
  return total;
}

}  // namespace fot
}  // namespace pcl
