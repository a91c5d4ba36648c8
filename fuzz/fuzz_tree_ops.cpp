// Fuzz target: the tree's writes and reads against a hash model. The input picks where the cells lie (near
// the origin or at the edges of the key range), a spacing and a memory cap, then writes cells and boxes of
// any state, directly and through accessors with and without LineBurstAccess, including keys beyond the
// range. Afterwards the tree must hold exactly the model's cells: counts, reads, Morton-ordered iteration,
// regions in a box, canonical form, the canonical pool and a tree written in the reverse order, the tree
// compacted by shrinkToFit and written again, a round
// trip through .fot and through OctoMap's .bt, and the nearest-cell search in both metrics against brute
// force.
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

#include <pcl_fot/io/fot_file.h>
#include <pcl_fot/io/octomap.h>
#include <pcl_fot/search/nearest_cell_search.h>
#include <pcl_fot/tree/accessor.h>
#include <pcl_fot/tree/fast_oct_tree.h>

namespace {

using namespace pcl::fot;
using Model = std::unordered_map<Key, CellState, KeyHash>;

void check(bool ok) {
  if (!ok) std::abort();
}

void apply(Model& m, const Key& k, CellState s) {
  if (s == CellState::Unknown)
    m.erase(k);
  else
    m[k] = s;
}

bool inBox(const Key& k, const Key& lo, const Key& hi) {
  return k.x >= lo.x && k.x <= hi.x && k.y >= lo.y && k.y <= hi.y && k.z >= lo.z && k.z <= hi.z;
}

Model cellsOf(const FastOctTree& t) {
  Model m;
  for (CellState s : {CellState::Occupied, CellState::Free})
    t.forEachCell(s, [&](const Key& k) { m[k] = s; });
  return m;
}

/** Morton order of tree coordinates, z the most significant axis at each level, as iteration runs. */
bool mortonLess(const Key& a, const Key& b) {
  const std::uint32_t u[3] = {tree_coord::fromKey(a.x), tree_coord::fromKey(a.y), tree_coord::fromKey(a.z)};
  const std::uint32_t v[3] = {tree_coord::fromKey(b.x), tree_coord::fromKey(b.y), tree_coord::fromKey(b.z)};
  int axis = 0;
  std::uint32_t top = 0;
  for (int i = 0; i < 3; ++i) {  // the axis whose coordinates differ in the highest bit; later axes win ties
    const std::uint32_t d = u[i] ^ v[i];
    if (!(d < top && d < (d ^ top))) axis = i, top = d;
  }
  return top != 0 && u[axis] < v[axis];
}

/** No block of eight uniform words below the root; returns the blocks reached. */
std::size_t canonicalBlocks(const FastOctTree& t, NodeWord w, unsigned level) {
  if (node::isBitmap(w)) return 0;
  check(level >= 2);
  const std::size_t first = node::childBase(w);
  check(first + 8 <= t.poolWords());
  bool all_uniform = true;
  std::size_t blocks = 1;
  for (unsigned o = 0; o < 8; ++o) {
    all_uniform = all_uniform && node::isUniform(t.words()[first + o]);
    blocks += canonicalBlocks(t, t.words()[first + o], level - 1);
  }
  check(!all_uniform);
  return blocks;
}

std::int64_t distance(Metric m, const Key& a, const Key& b) {
  const std::int64_t d[3] = {std::llabs(std::int64_t(a.x) - b.x), std::llabs(std::int64_t(a.y) - b.y),
                             std::llabs(std::int64_t(a.z) - b.z)};
  return m == Metric::Manhattan ? d[0] + d[1] + d[2] : d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
}

void checkSearch(const FastOctTree& t, const Model& model, const std::vector<Key>& queries) {
  for (CellState target : {CellState::Occupied, CellState::Free})
    for (Metric metric : {Metric::Manhattan, Metric::Euclidean}) {
      std::vector<CellMatch> all;
      for (const auto& kv : model)
        if (kv.second == target) all.push_back(CellMatch{kv.first, 0});
      NearestCellSearch search(t, metric, target);
      std::vector<CellMatch> got, batch;
      search.setNumberOfThreads(1 + queries.size() % 2);
      search.nearest(queries, batch);
      check(batch.size() == queries.size());
      for (std::size_t i = 0; i < queries.size(); ++i) {
        const Key& q = queries[i];
        for (CellMatch& c : all) c.distance = distance(metric, c.key, q);
        std::sort(all.begin(), all.end(), [](const CellMatch& a, const CellMatch& b) {
          return std::tie(a.distance, a.key.x, a.key.y, a.key.z) <
                 std::tie(b.distance, b.key.x, b.key.y, b.key.z);
        });
        CellMatch one;
        if (all.empty()) {
          check(!search.nearest(q, one) && !search.anyNearest(q, one) && batch[i].distance == -1);
          check(search.nearestK(q, 3, got) == 0 && search.radius(q, 1000, got) == 0);
          continue;
        }
        const std::int64_t best = all[0].distance;
        check(search.nearest(q, one) && one.key == all[0].key && one.distance == best);
        check(batch[i].key == all[0].key && batch[i].distance == best);
        check(!search.nearest(q, one, best - 1));
        check(search.anyNearest(q, one, NearestCellSearch::kUnbounded, best) && one.distance == best &&
              distance(metric, one.key, q) == best && model.at(one.key) == target);
        const std::size_t k = 1 + i % 6;
        check(search.nearestK(q, k, got) == std::min(k, all.size()));
        for (std::size_t j = 0; j < got.size(); ++j)
          check(got[j].key == all[j].key && got[j].distance == all[j].distance);
        const std::int64_t r = all[std::min<std::size_t>(i % 20, all.size() - 1)].distance;
        search.radius(q, r, got);
        std::size_t within = 0;
        while (within < all.size() && all[within].distance <= r) ++within;
        check(got.size() == within);
        for (std::size_t j = 0; j < within; ++j) check(got[j].key == all[j].key);
      }
    }
}

void checkTree(const FastOctTree& t, const Model& model, const std::vector<Key>& queries, const Key& lo,
               const Key& hi) {
  std::uint64_t counts[3] = {0, 0, 0};
  for (const auto& kv : model) ++counts[std::size_t(kv.second)];
  check(t.getOccupiedCount() == counts[std::size_t(CellState::Occupied)]);
  check(t.getFreeCount() == counts[std::size_t(CellState::Free)]);
  check(t.empty() == model.empty());
  for (CellState s : {CellState::Occupied, CellState::Free}) {
    std::vector<Key> seen;
    t.forEachCell(s, [&](const Key& k) { seen.push_back(k); });
    check(seen.size() == counts[std::size_t(s)]);
    for (std::size_t i = 0; i < seen.size(); ++i) {
      check(model.at(seen[i]) == s);
      check(i == 0 || mortonLess(seen[i - 1], seen[i]));
    }
  }
  for (const auto& kv : model) {
    check(t.getCell(kv.first) == kv.second);
    const Key beside{kv.first.x == kMaxKey ? kv.first.x - 1 : kv.first.x + 1, kv.first.y, kv.first.z};
    const auto it = model.find(beside);
    check(t.getCell(beside) == (it == model.end() ? CellState::Unknown : it->second));
  }
  check(canonicalBlocks(t, t.root().word, t.getDepth()) == t.getBlockCount());
  check(t.getNodeCount() == 1 + 8 * t.getBlockCount());
  check(t.poolWords() * sizeof(NodeWord) <= t.getMaxMemoryBytes());

  // Regions in the box: each overlaps it, and together they hold exactly the model's cells in it.
  std::uint64_t in_box = 0, covered = 0;
  for (const auto& kv : model) in_box += inBox(kv.first, lo, hi);
  t.forEachRegionInBox(lo, hi, [&](const Region& r) {
    const std::int64_t side = std::int64_t(1) << r.level;
    const std::int64_t from[3] = {std::max<std::int64_t>(r.min_key.x, lo.x),
                                  std::max<std::int64_t>(r.min_key.y, lo.y),
                                  std::max<std::int64_t>(r.min_key.z, lo.z)};
    const std::int64_t to[3] = {std::min<std::int64_t>(r.min_key.x + side - 1, hi.x),
                                std::min<std::int64_t>(r.min_key.y + side - 1, hi.y),
                                std::min<std::int64_t>(r.min_key.z + side - 1, hi.z)};
    check(from[0] <= to[0] && from[1] <= to[1] && from[2] <= to[2]);
    check(r.state != CellState::Unknown);
    covered += std::uint64_t(to[0] - from[0] + 1) * std::uint64_t(to[1] - from[1] + 1) *
               std::uint64_t(to[2] - from[2] + 1);
    for (const Key& c : {Key{std::int32_t(from[0]), std::int32_t(from[1]), std::int32_t(from[2])},
                         Key{std::int32_t(to[0]), std::int32_t(to[1]), std::int32_t(to[2])}})
      check(model.at(c) == r.state);
    return true;
  });
  check(covered == in_box);

  // The same cells written in the reverse order, into a fresh tree, give the same tree and the same pool.
  std::vector<std::pair<Key, CellState>> cells(model.begin(), model.end());
  std::sort(cells.begin(), cells.end(),
            [](const auto& a, const auto& b) { return mortonLess(b.first, a.first); });
  FastOctTree reversed(t.getGrid());
  for (const auto& c : cells) reversed.setCell(c.first, c.second);
  check(reversed == t);
  const FastOctTree::CanonicalPool pool = t.canonicalPool();
  check(reversed.canonicalPool().words == pool.words);
  check(FastOctTree::fromCanonicalPool(t.getGrid(), pool) == t);

  // shrinkToFit keeps every cell and leaves no free block, and the shrunk tree takes writes as before.
  FastOctTree shrunk = t, unshrunk = t;
  shrunk.shrinkToFit();
  check(shrunk == t && shrunk.canonicalPool().words == pool.words);
  check(shrunk.poolWords() == 8 * (1 + shrunk.getBlockCount()));
  for (FastOctTree* tree : {&shrunk, &unshrunk}) {
    tree->setMaxMemoryBytes(std::numeric_limits<std::size_t>::max());  // the shrunk pool has more room left
    for (std::size_t i = 0; i < queries.size(); ++i) tree->setCell(queries[i], CellState(i % 3));
  }
  check(shrunk == unshrunk);

  // Both file formats carry the cells over: .fot any map, .bt those within OctoMap's 65536³ cube.
  const std::string fot = io::encodeFot(t);
  check(io::encodeFot(reversed) == fot);
  check(io::decodeFot(fot.data(), fot.size()) == t);
  const bool in_octomap = std::all_of(model.begin(), model.end(), [](const auto& kv) {
    const Key& k = kv.first;
    return std::min({k.x, k.y, k.z}) >= -32768 && std::max({k.x, k.y, k.z}) <= 32767;
  });
  try {
    const std::string bt = io::encodeBt(t);
    check(in_octomap && io::decodeBt(bt.data(), bt.size()) == t);
  } catch (const std::invalid_argument&) {
    check(!in_octomap);
  }

  checkSearch(t, model, queries);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const Key kCentres[] = {{0, 0, 0},
                                 {kMaxKey - 100, kMaxKey - 100, kMaxKey - 100},
                                 {kMinKey + 100, kMinKey + 100, kMinKey + 100},
                                 {kMaxKey - 100, kMinKey + 100, 7}};
  static const std::int32_t kSpacings[] = {1, 2, 3, 5, 8, 16, 64, 1000};
  static const std::size_t kCaps[] = {0, 1 << 10, 4 << 10, 32 << 10};
  if (size < 1) return 0;
  const Key centre = kCentres[data[0] & 3];
  const std::int32_t spacing = kSpacings[(data[0] >> 2) & 7];
  FastOctTree tree(0.1);
  if (kCaps[(data[0] >> 5) & 3]) tree.setMaxMemoryBytes(kCaps[(data[0] >> 5) & 3]);
  Accessor burst(tree, true), plain(tree, false);
  Model model;
  std::vector<Key> queries;
  Key region_lo = centre, region_hi = centre;
  std::size_t budget = 20000;  // cells the model may write for boxes

  // Each 5 bytes: the operation and the state (first byte), a key, and a box's sides.
  for (std::size_t i = 1; i + 5 <= size; i += 5) {
    const std::uint8_t op = data[i] & 7;
    const CellState state = CellState((data[i] >> 3) % 3);
    const std::int64_t at[3] = {std::int64_t(centre.x) + std::int8_t(data[i + 1]) * spacing,
                                std::int64_t(centre.y) + std::int8_t(data[i + 2]) * spacing,
                                std::int64_t(centre.z) + std::int8_t(data[i + 3]) * spacing};
    const bool valid = std::all_of(at, at + 3, [](std::int64_t v) { return v >= kMinKey && v <= kMaxKey; });
    const Key key{std::int32_t(std::clamp<std::int64_t>(at[0], INT32_MIN, INT32_MAX)),
                  std::int32_t(std::clamp<std::int64_t>(at[1], INT32_MIN, INT32_MAX)),
                  std::int32_t(std::clamp<std::int64_t>(at[2], INT32_MIN, INT32_MAX))};
    if (op == 6) {  // a query, checked at the end, or a clear
      if (data[i + 4] == 0xFF) {
        tree.clear();
        model.clear();
      } else if (!valid) {  // refused by name, not searched
        bool refused = false;
        try {
          CellMatch m;
          NearestCellSearch(tree).nearest(key, m);
        } catch (const std::out_of_range&) {
          refused = true;
        }
        check(refused);
      } else if (queries.size() < 24) {
        queries.push_back(key);
      }
      continue;
    }
    if (op == 7) {  // the box checked for regions at the end
      region_lo = key;
      region_hi = Key{key.x + (data[i + 4] & 15) * spacing, key.y + ((data[i + 4] >> 4) & 15) * spacing,
                      key.z + spacing};
      if (!isValidKey(region_lo) || !isValidKey(region_hi)) region_lo = region_hi = centre;
      continue;
    }
    if (op == 3 || op == 4) {  // a box, sides 1 to 8
      const Key hi{key.x + (data[i + 4] & 7), key.y + ((data[i + 4] >> 3) & 7),
                   key.z + ((data[i + 4] >> 6) | (op == 4 ? 4 : 0))};
      const std::size_t cells =
          std::size_t(hi.x - key.x + 1) * std::size_t(hi.y - key.y + 1) * std::size_t(hi.z - key.z + 1);
      if (cells > budget) continue;
      budget -= cells;
      if (!valid || !isValidKey(hi)) {
        bool refused = false;
        try {
          tree.setBox(key, hi, state);
        } catch (const std::out_of_range&) {
          refused = true;
        }
        check(refused);
        continue;
      }
      try {
        tree.setBox(key, hi, state);
        for (std::int32_t z = key.z; z <= hi.z; ++z)
          for (std::int32_t y = key.y; y <= hi.y; ++y)
            for (std::int32_t x = key.x; x <= hi.x; ++x) apply(model, Key{x, y, z}, state);
      } catch (const MemoryLimitError&) {
        // The cubes written until then stay: every changed cell lies in the box and holds its state.
        Model now = cellsOf(tree);
        for (const Model* m : {&model, &now})
          for (const auto& kv : *m) {
            const auto a = model.find(kv.first), b = now.find(kv.first);
            const CellState was = a == model.end() ? CellState::Unknown : a->second;
            const CellState is = b == now.end() ? CellState::Unknown : b->second;
            check(was == is || (inBox(kv.first, key, hi) && is == state));
          }
        model.swap(now);
      }
      continue;
    }
    // A single cell: directly, or through an accessor with or without LineBurstAccess.
    const std::uint64_t counts[2] = {tree.getOccupiedCount(), tree.getFreeCount()};
    const std::size_t blocks = tree.getBlockCount();
    try {
      if (op == 0) {
        tree.setCell(key, state);
      } else if (op == 5) {  // at the cell's centre
        double x, y, z;
        tree.getGrid().keyToCenter(key, x, y, z);
        tree.setCellAtPoint(x, y, z, state);
      } else {
        (op == 1 ? burst : plain).setCell(key, state);
      }
      check(valid);
      apply(model, key, state);
    } catch (const std::out_of_range&) {
      check(!valid);
    } catch (const MemoryLimitError&) {  // the tree stays as it was
      check(valid && tree.getOccupiedCount() == counts[0] && tree.getFreeCount() == counts[1] &&
            tree.getBlockCount() == blocks);
      const auto it = model.find(key);
      check(tree.getCell(key) == (it == model.end() ? CellState::Unknown : it->second));
    }
    if (valid) check(burst.getCell(key) == tree.getCell(key) && plain.getCell(key) == tree.getCell(key));
  }
  checkTree(tree, model, queries, region_lo, region_hi);
  return 0;
}
