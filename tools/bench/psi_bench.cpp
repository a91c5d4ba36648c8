// Paper Table V and Fig. 5: ψ by the nearest-tree-neighbour against dmap_v on the 1024³ grid, and against
// nanoflann L1.
#include "sections.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <unordered_set>

#include <pcl/common/transforms.h>
#include <nanoflann.hpp>

#include <pcl_fot/io/file_io.h>
#include <pcl_fot/pcl/cloud_insertion.h>
#include <pcl_fot/psi/distance_map.h>
#include <pcl_fot/psi/psi.h>
#include <pcl_fot/search/nearest_cell_search.h>

#include "bench_util.h"

namespace fot_bench {
namespace {

using pcl::fot::CellState;
using pcl::fot::Key;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;
constexpr std::uint32_t kGridSide = 1024;

/** Two maps of one comparison, as cell keys. */
struct MapPair {
  std::string name;
  double res;
  std::vector<Key> a, b;
};

std::vector<Key> occupiedKeys(const Cloud& cloud, const pcl::fot::CellGrid& grid) {
  pcl::fot::FastOctTree tree(grid);
  pcl::fot::insertPointCloud(tree, cloud);
  std::vector<Key> keys;
  tree.forEachCell(CellState::Occupied, [&](const Key& k) { keys.push_back(k); });
  return keys;
}

MapPair scanPair(const BenchScan& a, const BenchScan& b, double res, const Eigen::Affine3f& b_pose,
                 const std::string& label) {
  const pcl::fot::CellGrid grid(res);
  Cloud moved;
  pcl::transformPointCloud(*b.cloud, moved, b_pose);
  return {format("%s (%.2f m)", label.c_str(), res), res, occupiedKeys(*a.cloud, grid),
          occupiedKeys(moved, grid)};
}

pcl::fot::FastOctTree treeOf(const std::vector<Key>& keys, const pcl::fot::CellGrid& grid) {
  pcl::fot::FastOctTree tree(grid);
  tree.insertKeys(keys.data(), keys.size());
  return tree;
}

/** The lowest key of both maps: the 1024³ grid's corner. False if the maps do not fit one grid. */
bool gridCorner(const MapPair& p, Key& lo) {
  lo = Key{pcl::fot::kMaxKey, pcl::fot::kMaxKey, pcl::fot::kMaxKey};
  Key hi{pcl::fot::kMinKey, pcl::fot::kMinKey, pcl::fot::kMinKey};
  for (const auto* keys : {&p.a, &p.b})
    for (const Key& k : *keys) {
      lo = Key{std::min(lo.x, k.x), std::min(lo.y, k.y), std::min(lo.z, k.z)};
      hi = Key{std::max(hi.x, k.x), std::max(hi.y, k.y), std::max(hi.z, k.z)};
    }
  return hi.x - lo.x < std::int32_t(kGridSide) && hi.y - lo.y < std::int32_t(kGridSide) &&
         hi.z - lo.z < std::int32_t(kGridSide);
}

struct PsiTimes {
  std::vector<double> tree, walks, dmap;  // ms per ψ
  std::uint64_t tree_sum = 0, walks_sum = 0, dmap_sum = 0;
};

/**
 * ψ's sums by the nearest-tree-neighbour walks alone: one query for every cell of each map into the other,
 * in the maps' Morton order, without ψ's bit windows. What the paper's method costs cell by cell.
 */
std::uint64_t walksAlone(const MapPair& p, const pcl::fot::FastOctTree& ta, const pcl::fot::FastOctTree& tb) {
  std::uint64_t sum = 0;
  for (const auto& [from, to] : {std::make_pair(&p.a, &tb), std::make_pair(&p.b, &ta)}) {
    pcl::fot::NearestCellSearch search(*to);
    pcl::fot::CellMatch m;
    for (const Key& k : *from)
      if (search.anyNearest(k, m)) sum += std::uint64_t(m.distance);
  }
  return sum;
}

/**
 * dmap_v's distance map, one for the whole run, as a program comparing many maps would keep it. Its first
 * use also faults in the 2 GiB, which on a virtual machine can take longer than the transform: that call
 * is timed apart and not counted.
 */
struct DmapStorage {
  pcl::fot::DistanceMap map;
  double first_ms = -1;
};

PsiTimes timePsi(const MapPair& p, int tree_repeats, int dmap_repeats, DmapStorage& storage) {
  const pcl::fot::CellGrid grid(p.res);
  const pcl::fot::FastOctTree ta = treeOf(p.a, grid), tb = treeOf(p.b, grid);
  PsiTimes t;
  for (int r = 0; r < tree_repeats; ++r) {
    scrubCaches();
    t.tree.push_back(timeOnce([&] { t.tree_sum = pcl::fot::psi(ta, tb).sum; }) * 1e3);
    scrubCaches();
    t.walks.push_back(timeOnce([&] { t.walks_sum = walksAlone(p, ta, tb); }) * 1e3);
  }
  Key lo;
  if (!gridCorner(p, lo)) throw std::runtime_error(p.name + " does not fit a 1024³ grid");
  pcl::fot::FastOccMesh ga(grid, kGridSide, lo), gb(grid, kGridSide, lo);
  ga.insertKeys(p.a.data(), p.a.size());
  gb.insertKeys(p.b.data(), p.b.size());
  if (storage.first_ms < 0)
    storage.first_ms = timeOnce([&] { pcl::fot::psiByDistanceMaps(ga, gb, storage.map); }) * 1e3;
  for (int r = 0; r < dmap_repeats; ++r)
    t.dmap.push_back(timeOnce([&] { t.dmap_sum = pcl::fot::psiByDistanceMaps(ga, gb, storage.map).sum; }) *
                     1e3);
  return t;
}

/** nanoflann's dataset adaptor over voxel centres, in cell units. */
struct Centres {
  std::vector<float> xyz;
  explicit Centres(const std::vector<Key>& keys) {
    for (const Key& k : keys) xyz.insert(xyz.end(), {float(k.x), float(k.y), float(k.z)});
  }
  std::size_t kdtree_get_point_count() const { return xyz.size() / 3; }
  float kdtree_get_pt(std::size_t i, std::size_t d) const { return xyz[3 * i + d]; }
  template <typename Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};
using NanoL1 =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L1_Adaptor<float, Centres>, Centres, 3, unsigned>;

/** ψ's two directed sums with nanoflann L1 trees, built from the voxel centres. */
double nanoflannPsi(const Centres& a, const Centres& b) {
  auto directed = [](const Centres& from, const Centres& to) {
    NanoL1 tree(3, to, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    tree.buildIndex();
    double sum = 0;
    for (std::size_t i = 0; i < from.kdtree_get_point_count(); ++i) {
      unsigned idx;
      float d;
      tree.knnSearch(&from.xyz[3 * i], 1, &idx, &d);
      sum += d;
    }
    return sum;
  };
  return directed(a, b) + directed(b, a);
}

std::string tableV(const std::vector<MapPair>& pairs, int dmap_repeats, DmapStorage& storage,
                   std::vector<std::string>& verdicts) {
  Table t({"maps", "cells a / b", "tree ψ mean ms", "variance", "dmap_v mean ms", "variance", "speed-up",
           "tree ψ ns / cell", "walks alone ns / cell", "same ψ"});
  double worst = 1e300, best = 0, dmap_low = 1e300, dmap_high = 0;
  std::size_t met = 0, largest_met = 0, smallest_missed = ~std::size_t(0);  // rows, and their cells a + b
  // On the rows that miss, ns per cell: what 10,000× would leave, what tree ψ takes, what a walk takes.
  double budget_low = 1e300, budget_high = 0, cost_low = 1e300, cost_high = 0, walk_low = 1e300,
         walk_high = 0;
  for (const MapPair& p : pairs) {
    std::fprintf(stderr, "  psi: Table V, %s\n", p.name.c_str());
    const PsiTimes times = timePsi(p, 5, dmap_repeats, storage);
    const double speedup = mean(times.dmap) / mean(times.tree);
    worst = std::min(worst, speedup);
    best = std::max(best, speedup);
    dmap_low = std::min(dmap_low, mean(times.dmap));
    dmap_high = std::max(dmap_high, mean(times.dmap));
    const std::size_t cells = p.a.size() + p.b.size();
    const double per_cell = mean(times.tree) * 1e6 / double(cells),
                 per_walk = median(times.walks) * 1e6 / double(cells);
    if (speedup >= 10000) {
      ++met;
      largest_met = std::max(largest_met, cells);
    } else {
      smallest_missed = std::min(smallest_missed, cells);
      const double budget = mean(times.dmap) * 1e6 / 1e4 / double(cells);
      budget_low = std::min(budget_low, budget), budget_high = std::max(budget_high, budget);
      cost_low = std::min(cost_low, per_cell), cost_high = std::max(cost_high, per_cell);
      walk_low = std::min(walk_low, per_walk), walk_high = std::max(walk_high, per_walk);
    }
    t.add({p.name, format("%zu / %zu", p.a.size(), p.b.size()), format("%.3f", mean(times.tree)),
           format("%.5f", variance(times.tree)), format("%.0f", mean(times.dmap)),
           format("%.0f", variance(times.dmap)), format("**%.0f×**", speedup), format("%.0f", per_cell),
           format("%.0f", per_walk),
           times.tree_sum == times.dmap_sum && times.tree_sum == times.walks_sum ? "yes" : "**NO**"});
  }
  std::string verdict = format(
      "Table V: tree ψ is **%.0f× to %.0f×** faster than dmap_v at 1024³ on the real scans "
      "(target 10,000×; the paper: 1,376× to 39,255×).",
      worst, best);
  if (met < pairs.size())
    verdict += format(
        " 10,000× holds on %zu of %zu rows. dmap_v takes %.1f–%.1f s whatever the maps, as it transforms the "
        "whole grid, so 10,000× leaves tree ψ %.2f–%.2f ms; ψ's cost grows with the cells compared, and "
        "the rows that miss compare %zu cells or more (a + b)%s.",
        met, pairs.size(), dmap_low / 1e3, dmap_high / 1e3, dmap_low / 1e4, dmap_high / 1e4, smallest_missed,
        met > 0 ? format(", those that meet it at most %zu", largest_met).c_str() : "");
  if (met < pairs.size())
    verdict += format(
        " There 10,000× would leave %.0f–%.0f ns per cell; tree ψ takes %.0f–%.0f ns, and the "
        "nearest-tree-neighbour walk of the paper, every cell searched alone, %.0f–%.0f ns.",
        budget_low, budget_high, cost_low, cost_high, walk_low, walk_high);
  verdicts.push_back(verdict);
  return format(
             "### Real scans (paper Table V)\n\n"
             "Pairs of scans of one scene, as the paper compares consecutive frames. The Kinect frames in "
             "their own "
             "frames (the camera barely moved); room_scan2 placed on room_scan1 by the NDT tutorial's "
             "initial guess. "
             "Times are the mean and variance (ms²) of 5 tree ψ runs and %d dmap_v runs; dmap_v builds both "
             "maps' "
             "distance maps on the 1024³ grid, one after the other in one 2 GiB map that every run reuses, "
             "and reads them off at the other map's cells (the run's first call, which also faulted that "
             "memory in, took %.0f ms and is not counted). "
             "\"Walks alone\" is the median of 5 runs of the same sums by the nearest-tree-neighbour search "
             "only, one query per cell, without tree ψ's bit windows.\n\n",
             dmap_repeats, storage.first_ms) +
         t.markdown();
}

std::string versusNanoflann(const std::vector<MapPair>& pairs, int repeats,
                            std::vector<std::string>& verdicts) {
  Table t({"maps", "cells a / b", "tree ψ ms", "tree ψ, 2 threads ms", "nanoflann L1 ms", "nanoflann / tree",
           "same ψ"});
  double worst = 1e300;
  for (const MapPair& p : pairs) {
    std::fprintf(stderr, "  psi: against nanoflann, %s\n", p.name.c_str());
    const pcl::fot::CellGrid grid(p.res);
    const pcl::fot::FastOctTree ta = treeOf(p.a, grid), tb = treeOf(p.b, grid);
    const Centres ca(p.a), cb(p.b);
    std::vector<double> tree, threaded, nano;
    std::uint64_t sum = 0, sum_threaded = 0;
    double nano_sum = 0;
    pcl::fot::PsiOptions two;
    two.threads = 2;
    for (int r = 0; r < repeats; ++r) {
      scrubCaches();
      tree.push_back(timeOnce([&] { sum = pcl::fot::psi(ta, tb).sum; }) * 1e3);
      scrubCaches();
      threaded.push_back(timeOnce([&] { sum_threaded = pcl::fot::psi(ta, tb, two).sum; }) * 1e3);
      scrubCaches();
      nano.push_back(timeOnce([&] { nano_sum = nanoflannPsi(ca, cb); }) * 1e3);
    }
    const double ratio = median(nano) / median(tree);
    worst = std::min(worst, ratio);
    t.add({p.name, format("%zu / %zu", p.a.size(), p.b.size()), format("%.2f", median(tree)),
           format("%.2f", median(threaded)), format("%.2f", median(nano)), format("**%.2f×**", ratio),
           sum == std::uint64_t(nano_sum) && sum == sum_threaded ? "yes" : "**NO**"});
  }
  verdicts.push_back(
      format("Tree ψ against the same sums with nanoflann L1 (build included): at least **%.2f×** "
             "faster (target 2×).",
             worst));
  return format(
             "### Against nanoflann\n\n"
             "The same ψ as two nanoflann L1 k-d trees give it: each map's voxel centres (in cell units) "
             "indexed, "
             "then 1-NN of every cell of the other map; index build included, extracting the centres not. "
             "Medians "
             "of %d runs. The tree ψ reads the maps as they are.\n\n",
             repeats) +
         t.markdown();
}

/** n distinct uniformly random cells in the 1024³ cube: a map holds a cell once, nanoflann would count it
 * twice. */
std::vector<Key> randomCells(int n, std::mt19937& rng) {
  std::uniform_int_distribution<std::int32_t> coord(0, kGridSide - 1);
  std::unordered_set<std::uint64_t> seen;
  std::vector<Key> keys;
  while (keys.size() < std::size_t(n)) {
    const Key k{coord(rng), coord(rng), coord(rng)};
    if (seen.insert(std::uint64_t(k.x) | std::uint64_t(k.y) << 10 | std::uint64_t(k.z) << 20).second)
      keys.push_back(k);
  }
  return keys;
}

/** Fig. 5: uniform random cells in the 1024³ cube, with nanoflann L1 beside. */
std::string figure5(int repeats, const std::string& plot_file, DmapStorage& storage,
                    std::vector<std::string>& verdicts) {
  const int sizes[] = {100, 300, 1000, 3000, 10000, 30000, 100000};
  std::mt19937 rng(5);
  Table t({"cells per map", "tree ψ median ms", "walks alone ms", "dmap_v ms", "speed-up", "nanoflann L1 ms",
           "nanoflann / tree"});
  std::string data;
  double nano_low = 1e300, nano_high = 0, walks_low = 1e300, walks_high = 0;  // ratios to nanoflann
  for (int n : sizes) {
    std::fprintf(stderr, "  psi: Fig. 5, %d random cells\n", n);
    MapPair p{format("%d random", n), 0.05, randomCells(n, rng), randomCells(n, rng)};
    const PsiTimes times = timePsi(p, repeats, 1, storage);
    const Centres ca(p.a), cb(p.b);
    std::vector<double> nano;
    double nano_sum = 0;
    for (int r = 0; r < repeats; ++r) {
      scrubCaches();
      nano.push_back(timeOnce([&] { nano_sum = nanoflannPsi(ca, cb); }) * 1e3);
    }
    const double tree = median(times.tree), walks = median(times.walks), dmap = times.dmap[0],
                 ratio = median(nano) / tree;
    nano_low = std::min(nano_low, ratio);
    nano_high = std::max(nano_high, ratio);
    walks_low = std::min(walks_low, walks / median(nano));
    walks_high = std::max(walks_high, walks / median(nano));
    t.add({format("%d", n), format("%.3f", tree), format("%.3f", walks), format("%.0f", dmap),
           format("%.0f×", dmap / tree), format("%.3f", median(nano)), format("%.2f×", ratio)});
    data += format("%d %.6f %.3f %.3f %.6f\n", n, tree, dmap, dmap / tree, median(nano));
    if (times.tree_sum != times.dmap_sum || times.tree_sum != times.walks_sum ||
        times.tree_sum != std::uint64_t(nano_sum))
      verdicts.push_back(format("**ψ differs** for %d random cells", n));
  }
  std::string verdict =
      format("Random maps (Fig. 5): nanoflann L1 takes %.2f× to %.2f× tree ψ's time.", nano_low, nano_high);
  if (nano_low < 2)
    verdict += format(
        " Where below 2×: a random cell hangs alone below a chain of single-child nodes, which the walk "
        "descends link by link, while nanoflann's leaf buckets fit the points. The nearest-tree-neighbour "
        "walks alone, one per cell and nothing else, take %.2f× to %.2f× nanoflann's whole ψ, build "
        "included.",
        walks_low, walks_high);
  verdicts.push_back(verdict);
  std::string plot;
  const std::string data_file = plot_file + ".dat", script_file = plot_file + ".gp";
  pcl::fot::io::writeFileAtomically(data_file, data);
  pcl::fot::io::writeFileAtomically(
      script_file,
      format("set terminal pngcairo size 900,600\nset output '%s.tmp'\nset logscale xy\nset grid\n"
             "set xlabel 'cells per map'\nset ylabel 'ms (speed-up: ratio)'\n"
             "set title 'psi on random maps in a 1024^3 cube'\nset key top left\n"
             "plot '%s' using 1:2 with linespoints title 'tree psi (ms)', "
             "'' using 1:3 with linespoints title 'dmap_v (ms)', "
             "'' using 1:4 with linespoints title 'speed-up dmap_v / tree', "
             "'' using 1:5 with linespoints title 'nanoflann L1 (ms)'\n",
             plot_file.c_str(), data_file.c_str()));
  const std::string command =
      "gnuplot '" + script_file + "' && mv '" + plot_file + ".tmp' '" + plot_file + "'";
  if (std::system(command.c_str()) == 0) {
    plot = format("![ψ on random maps](%s)\n\n", plot_file.substr(plot_file.rfind('/') + 1).c_str());
  } else {
    std::fprintf(stderr, "  psi: gnuplot failed; the table has the figures\n");
  }
  std::remove(data_file.c_str());
  std::remove(script_file.c_str());
  return "### Random maps (paper Fig. 5)\n\n"
         "Two maps of n distinct uniformly random cells each in the 1024³ cube; tree ψ, the walks alone (as "
         "in Table V) and nanoflann L1 (as above, build included) are medians of " +
         std::to_string(repeats) + " runs, dmap_v one run in the reused map of Table V. Log axes.\n\n" +
         plot + t.markdown();
}

}  // namespace

std::string benchPsi(const std::vector<BenchScan>& scans, int repeats, int dmap_repeats,
                     const std::string& plot_file) {
  const Eigen::Affine3f identity = Eigen::Affine3f::Identity();
  const Eigen::Affine3f ndt_guess =
      Eigen::Translation3f(1.79387f, 0.720047f, 0.0f) * Eigen::AngleAxisf(0.6931f, Eigen::Vector3f::UnitZ());
  const BenchScan &k1 = findScan(scans, "kinect_capture0001"), &k2 = findScan(scans, "kinect_capture0002"),
                  &k3 = findScan(scans, "kinect_capture0003"), &r1 = findScan(scans, "room_scan1"),
                  &r2 = findScan(scans, "room_scan2");
  std::vector<MapPair> pairs;
  for (double res : {0.05, 0.02, 0.01}) {
    pairs.push_back(scanPair(k1, k2, res, identity, "kinect 1 / 2"));
    pairs.push_back(scanPair(k2, k3, res, identity, "kinect 2 / 3"));
  }
  for (double res : {0.1, 0.05}) pairs.push_back(scanPair(r1, r2, res, ndt_guess, "room 1 / 2"));

  std::vector<std::string> verdicts;
  std::string out = "## Map similarity ψ (paper §IV–V)\n\n";
  out +=
      "ψ of two binary maps (occupied cells), exact: each table checks that every method gives the same "
      "sum.\n\n";
  DmapStorage storage;
  out += tableV(pairs, dmap_repeats, storage, verdicts) + "\n";
  out += versusNanoflann(pairs, repeats, verdicts) + "\n";
  out += figure5(repeats, plot_file, storage, verdicts) + "\n";
  out += "Summary:\n\n";
  for (const auto& v : verdicts) out += "- " + v + "\n";
  return out;
}

}  // namespace fot_bench
