#pragma once
// Tests' checks against OctoMap: a map holds exactly an OctoMap tree's cells (any occupancy tree type), and a
// damaged file is refused cleanly or loads a map OctoMap reads.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>
#include <octomap/OcTreeKey.h>

#include <pcl_fot/io/octomap.h>
#include <pcl_fot/tree/fast_oct_tree.h>

/**
 * Expects `ours` to hold exactly OctoMap's free and occupied cells: every OctoMap leaf is a box of one
 * state in ours, and the cell counts agree, so nothing else is known in ours either.
 */
template <typename OctoMapTree>
void expectSameCells(const OctoMapTree& om, const pcl::fot::FastOctTree& ours) {
  using namespace pcl::fot;
  const double res = om.getResolution();
  ASSERT_DOUBLE_EQ(ours.getResolution(), res);
  std::uint64_t occupied = 0, free = 0;
  for (auto it = om.begin_leafs(); it != om.end_leafs(); ++it) {
    const std::uint64_t side = std::uint64_t(1) << (16 - it.getDepth());
    const octomap::OcTreeKey k = it.getIndexKey();
    const CellState want = om.isNodeOccupied(*it) ? CellState::Occupied : CellState::Free;
    (want == CellState::Occupied ? occupied : free) += side * side * side;
    // OctoMap key K is cell floor(c / res) + 32768; ours is floor((c - origin) / res).
    Key lo;
    for (int a = 0; a < 3; ++a)
      (&lo.x)[a] = std::int32_t(k[a]) - 32768 - std::int32_t(std::lround(ours.getGrid().origin()[a] / res));
    const Key hi{lo.x + std::int32_t(side) - 1, lo.y + std::int32_t(side) - 1, lo.z + std::int32_t(side) - 1};
    std::uint64_t covered = 0;
    bool same = true;
    ours.forEachRegionInBox(lo, hi, [&](const Region& r) {
      same = same && r.state == want;
      std::uint64_t v = 1;
      const std::int64_t rs = std::int64_t(1) << r.level;
      const std::int64_t rl[3] = {r.min_key.x, r.min_key.y, r.min_key.z}, bl[3] = {lo.x, lo.y, lo.z},
                         bh[3] = {hi.x, hi.y, hi.z};
      for (int a = 0; a < 3; ++a)
        v *= std::uint64_t(std::min(rl[a] + rs - 1, bh[a]) - std::max(rl[a], bl[a]) + 1);
      covered += v;
    });
    ASSERT_TRUE(same && covered == side * side * side)
        << "OctoMap leaf at " << toString(lo) << ", side " << side;
  }
  EXPECT_EQ(ours.getOccupiedCount(), occupied);
  EXPECT_EQ(ours.getFreeCount(), free);
}

/**
 * True if decode(bytes) loads a map, which OctoMap must then read back from our .bt; false if it refuses the
 * bytes with FormatError, MemoryLimitError (past the cap) or std::invalid_argument (a header number gone
 * wrong). Anything else escapes and fails the test.
 */
template <typename Decode>
bool loadsAValidMap(Decode&& decode, const std::string& bytes) {
  using namespace pcl::fot;
  try {
    const FastOctTree t = decode(bytes);
    std::istringstream in(io::encodeBt(t));
    octomap::OcTree check(0.1);
    EXPECT_TRUE(check.readBinary(in));
    return true;
  } catch (const io::FormatError&) {
  } catch (const MemoryLimitError&) {
  } catch (const std::invalid_argument&) {
  }
  return false;
}
