// The map: FastOctTree with its scans, cells, merge, files and ψ.

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <pcl_fot/io/fot_file.h>
#include <pcl_fot/io/octomap.h>
#include <pcl_fot/mapping/scan_insertion.h>
#include <pcl_fot/psi/psi.h>
#include <pcl_fot/tree/fast_oct_tree.h>
#include <pcl_fot/tree/tree_coord.h>

#include "arrays.h"
#include "bindings.h"

namespace pcl_fot_python {
namespace {

using pcl::fot::CellState;
using pcl::fot::FastOctTree;
using pcl::fot::Key;
using pcl::fot::UpdateRule;

UpdateRule toRule(const std::string& rule) {
  if (rule == "binary") return UpdateRule::Binary;
  if (rule == "log_odds") return UpdateRule::LogOdds;
  throw py::value_error("rule must be 'binary' or 'log_odds', not '" + rule + "'");
}

std::string ruleName(UpdateRule rule) {
  return rule == UpdateRule::LogOdds ? "log_odds" : "binary";
}

py::dict statsDict(const pcl::fot::ScanStats& s) {
  py::dict d;
  d["rays"] = s.rays;
  d["occupied"] = s.occupied;
  d["truncated"] = s.truncated;
  d["too_close"] = s.too_close;
  d["non_finite"] = s.non_finite;
  d["out_of_range"] = s.out_of_range;
  d["outside_region"] = s.outside_region;
  d["ray_cells"] = s.ray_cells;
  d["free_cells"] = s.free_cells;
  d["skipped_cells"] = s.skipped_cells;
  return d;
}

/** The region a tuple ((x0, y0, z0), (x1, y1, z1)) of keys names, bounds included. */
pcl::fot::KeyBox toRegion(const py::handle& obj) {
  const py::array_t<std::int64_t, py::array::c_style | py::array::forcecast> a =
      py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(obj);
  if (!a || a.size() != 6) throw py::value_error("region must be two keys: ((x0, y0, z0), (x1, y1, z1))");
  std::int32_t v[6];
  for (int i = 0; i < 6; ++i) {
    if (a.data()[i] < pcl::fot::kMinKey || a.data()[i] > pcl::fot::kMaxKey)
      throw py::value_error("region: a key lies beyond the key range");
    v[i] = std::int32_t(a.data()[i]);
  }
  if (v[0] > v[3] || v[1] > v[4] || v[2] > v[5])
    throw py::value_error("region: the first key must be the lower");
  return pcl::fot::KeyBox{Key{v[0], v[1], v[2]}, Key{v[3], v[4], v[5]}};
}

/** The options of a scan, checked. */
pcl::fot::ScanOptions scanOptions(double max_range, double min_range, bool discretize, unsigned threads,
                                  const py::object& region) {
  pcl::fot::ScanOptions options;
  options.max_range = max_range;
  options.min_range = min_range;
  options.discretize = discretize;
  options.threads = threads;
  if (!region.is_none()) options.region = toRegion(region);
  return options;
}

/**
 * A scan's points in the map frame, and its sensor. Without an orientation the points are in the map frame
 * and `origin` is the sensor; with one (w, x, y, z) they are in the sensor frame and (origin, orientation)
 * is the sensor pose, applied as pcl::fot::insertScan applies it.
 */
class MapFrameScan {
 public:
  MapFrameScan(const py::handle& points, const py::handle& origin, const py::object& orientation)
      : input_(toPoints(points, "points")) {
    const std::array<double, 3> o = toTriple(origin, "origin");
    for (int a = 0; a < 3; ++a) sensor_[a] = float(o[a]);
    if (orientation.is_none()) return;
    const py::array_t<double, py::array::c_style | py::array::forcecast> q =
        py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(orientation);
    if (!q || q.size() != 4 || !std::isfinite(q.data()[0]) || !std::isfinite(q.data()[1]) ||
        !std::isfinite(q.data()[2]) || !std::isfinite(q.data()[3]))
      throw py::value_error("orientation must be four finite numbers: w, x, y, z");
    const Eigen::Quaternionf rotation(float(q.data()[0]), float(q.data()[1]), float(q.data()[2]),
                                      float(q.data()[3]));
    if (rotation.norm() == 0.0f) throw py::value_error("orientation must not be zero");
    const Eigen::Affine3f pose =
        Eigen::Translation3f(sensor_[0], sensor_[1], sensor_[2]) * rotation.normalized();
    mapped_.resize(3 * size());
    for (std::size_t i = 0; i < size(); ++i) {
      const Eigen::Vector3f p = pose * Eigen::Map<const Eigen::Vector3f>(input_.data() + 3 * i);
      for (int a = 0; a < 3; ++a) mapped_[3 * i + a] = p[a];
    }
  }

  const float* sensor() const { return sensor_; }
  const float* xyz() const { return mapped_.empty() ? input_.data() : mapped_.data(); }
  std::size_t size() const { return std::size_t(input_.shape(0)); }

 private:
  Points input_;
  std::vector<float> mapped_;
  float sensor_[3];
};

py::dict insertScan(FastOctTree& map, const py::handle& points, const py::handle& origin,
                    const py::object& orientation, double max_range, double min_range, bool discretize,
                    unsigned threads, const py::object& region) {
  const MapFrameScan scan(points, origin, orientation);
  const pcl::fot::ScanOptions options = scanOptions(max_range, min_range, discretize, threads, region);
  pcl::fot::ScanStats stats;
  {
    py::gil_scoped_release unlocked;
    stats = pcl::fot::insertRays(map, scan.sensor(), scan.xyz(), scan.size(), 3 * sizeof(float), options);
  }
  return statsDict(stats);
}

/** numpy's view of pcl::fot::ScanBlock. */
py::dtype scanBlockType() {
  static_assert(sizeof(pcl::fot::ScanBlock) == 32, "the dtype below spells ScanBlock's layout");
  py::dict spec;
  spec["names"] = py::make_tuple("at", "passed", "hit");
  spec["formats"] = py::make_tuple(py::make_tuple("<u4", 3), "<u8", "<u8");
  spec["offsets"] = py::make_tuple(offsetof(pcl::fot::ScanBlock, at), offsetof(pcl::fot::ScanBlock, passed),
                                   offsetof(pcl::fot::ScanBlock, hit));
  spec["itemsize"] = sizeof(pcl::fot::ScanBlock);
  return py::dtype::from_args(spec);
}

py::tuple traceScan(const FastOctTree& map, const py::handle& points, const py::handle& origin,
                    const py::object& orientation, double max_range, double min_range, bool discretize,
                    unsigned threads) {
  const MapFrameScan scan(points, origin, orientation);
  const pcl::fot::ScanOptions options = scanOptions(max_range, min_range, discretize, threads, py::none());
  pcl::fot::ScanStats stats;
  std::vector<pcl::fot::ScanBlock> blocks;
  {
    py::gil_scoped_release unlocked;
    blocks =
        pcl::fot::traceScan(map, scan.sensor(), scan.xyz(), scan.size(), 3 * sizeof(float), options, &stats);
  }
  const py::array out(scanBlockType(), std::vector<py::ssize_t>{py::ssize_t(blocks.size())}, blocks.data());
  return py::make_tuple(out, statsDict(stats));
}

/** The blocks of a traced scan, checked: the dtype of traceScan's arrays, one dimension, contiguous. */
py::array toBlocks(const py::handle& obj) {
  const py::array a = py::array::ensure(obj);
  if (!a || !a.dtype().equal(scanBlockType()) || a.ndim() != 1)
    throw py::type_error("blocks must be a one-dimensional array that trace_scan returned");
  return py::array::ensure(a, py::array::c_style);
}

/** A block's lowest key; false if the block reaches beyond the key range. */
bool blockKey(const pcl::fot::ScanBlock& b, Key& key) {
  if (b.at[0] >= (1u << 30) || b.at[1] >= (1u << 30) || b.at[2] >= (1u << 30)) return false;
  key = pcl::fot::TreeCoord(4 * b.at[0], 4 * b.at[1], 4 * b.at[2]).key();
  return pcl::fot::isValidKey(key) && pcl::fot::isValidKey(Key{key.x + 3, key.y + 3, key.z + 3});
}

std::uint64_t applyScan(FastOctTree& map, const py::handle& blocks, const py::object& region) {
  const py::array b = toBlocks(blocks);
  pcl::fot::ScanOptions options;
  if (!region.is_none()) options.region = toRegion(region);
  const auto* data = static_cast<const pcl::fot::ScanBlock*>(b.data());
  Key key;
  for (py::ssize_t i = 0; i < b.size(); ++i)
    if (!blockKey(data[i], key)) throw py::value_error("blocks: a block lies beyond the key range");
  py::gil_scoped_release unlocked;
  return pcl::fot::applyScan(map, data, std::size_t(b.size()), options);
}

/** The lowest key of each block, (N, 3) int32: a block of tile level L >= 2 lies in tile key >> L. */
py::array_t<std::int32_t> blockKeys(const py::handle& blocks) {
  const py::array b = toBlocks(blocks);
  const auto* data = static_cast<const pcl::fot::ScanBlock*>(b.data());
  py::array_t<std::int32_t> keys = newArray<std::int32_t>(std::size_t(b.size()), 3);
  std::int32_t* k = keys.mutable_data();
  for (py::ssize_t i = 0; i < b.size(); ++i) {
    Key key;
    if (!blockKey(data[i], key)) throw py::value_error("blocks: a block lies beyond the key range");
    k[3 * i] = key.x, k[3 * i + 1] = key.y, k[3 * i + 2] = key.z;
  }
  return keys;
}

/** `read(key)` for each row of `keys`, into a new array of T. */
template <typename T, typename Read>
py::array_t<T> perKey(const py::handle& keys, Read&& read) {
  const Keys k = toKeys(keys, "keys");
  const std::size_t n = std::size_t(k.shape(0));
  py::array_t<T> out = newArray<T>(n);
  T* o = out.mutable_data();
  const std::int32_t* v = k.data();
  for (std::size_t i = 0; i < n; ++i) {
    const Key key{v[3 * i], v[3 * i + 1], v[3 * i + 2]};
    if (!pcl::fot::isValidKey(key))
      throw py::value_error("keys: " + pcl::fot::toString(key) + " lies beyond the key range");
    o[i] = read(key);
  }
  return out;
}

py::tuple cells(const FastOctTree& map) {
  std::vector<std::int32_t> corners;
  std::vector<std::uint8_t> levels;
  std::vector<float> values;
  map.forEachLogOdds([&](const pcl::fot::Region& r, float value) {
    corners.insert(corners.end(), {r.min_key.x, r.min_key.y, r.min_key.z});
    levels.push_back(std::uint8_t(r.level));
    values.push_back(value);
    return true;
  });
  py::array_t<std::int32_t> c = newArray<std::int32_t>(levels.size(), 3);
  std::copy(corners.begin(), corners.end(), c.mutable_data());
  return py::make_tuple(c, toArray(levels), toArray(values));
}

py::array_t<double> occupiedCenters(const FastOctTree& map) {
  std::vector<double> xyz;
  map.forEachCell(CellState::Occupied, [&](const Key& k) {
    double c[3];
    map.getGrid().keyToCenter(k, c[0], c[1], c[2]);
    xyz.insert(xyz.end(), c, c + 3);
  });
  py::array_t<double> out = newArray<double>(xyz.size() / 3, 3);
  std::copy(xyz.begin(), xyz.end(), out.mutable_data());
  return out;
}

void save(const FastOctTree& map, const std::string& path) {
  const std::string e = extensionOf(path);
  if (e == ".fot") return pcl::fot::io::saveFot(map, path);
  if (e == ".bt") return pcl::fot::io::saveBt(map, path);
  if (e == ".ot") return pcl::fot::io::saveOt(map, path);
  throw py::value_error("save: '" + path + "' must end in .fot, .bt or .ot");
}

FastOctTree load(const std::string& path) {
  const std::string e = extensionOf(path);
  if (e == ".fot") return pcl::fot::io::loadFot(path);
  if (e == ".bt") return pcl::fot::io::loadBt(path);
  if (e == ".ot") return pcl::fot::io::loadOt(path);
  throw py::value_error("load: '" + path + "' must end in .fot, .bt or .ot");
}

}  // namespace

void bindMap(py::module_& m) {
  py::class_<pcl::fot::SensorModel>(m, "SensorModel",
                                    "OctoMap's sensor model: hit and miss probabilities, clamps, threshold.")
      .def(py::init<double, double, double, double, double>(), py::arg("prob_hit") = 0.7,
           py::arg("prob_miss") = 0.4, py::arg("clamp_min") = 0.1192, py::arg("clamp_max") = 0.971,
           py::arg("occupancy") = 0.5)
      .def_property_readonly("prob_hit", &pcl::fot::SensorModel::probHit)
      .def_property_readonly("prob_miss", &pcl::fot::SensorModel::probMiss)
      .def_property_readonly("clamp_min", &pcl::fot::SensorModel::clampMin)
      .def_property_readonly("clamp_max", &pcl::fot::SensorModel::clampMax)
      .def_property_readonly("occupancy", &pcl::fot::SensorModel::occupancy);

  py::class_<FastOctTree>(m, "FastOctTree", "An occupancy map of 4-byte nodes (the FastOctTree).")
      .def(py::init([](double resolution, const py::handle& origin, const std::string& rule,
                       const pcl::fot::SensorModel& model) {
             const std::array<double, 3> o = toTriple(origin, "origin");
             FastOctTree map(resolution, o[0], o[1], o[2]);
             map.setUpdateRule(toRule(rule));
             map.setSensorModel(model);
             return map;
           }),
           py::arg("resolution"), py::arg("origin") = py::make_tuple(0.0, 0.0, 0.0),
           py::arg("rule") = "binary", py::arg("sensor_model") = pcl::fot::SensorModel())
      .def_property_readonly("resolution", &FastOctTree::getResolution)
      .def_property_readonly("origin",
                             [](const FastOctTree& t) {
                               const double* o = t.getGrid().origin();
                               return py::make_tuple(o[0], o[1], o[2]);
                             })
      .def_property_readonly("rule", [](const FastOctTree& t) { return ruleName(t.getUpdateRule()); })
      .def_property_readonly("sensor_model", &FastOctTree::getSensorModel)
      .def("insert_scan", &insertScan, py::arg("points"), py::arg("origin"),
           py::arg("orientation") = py::none(), py::kw_only(), py::arg("max_range") = -1.0,
           py::arg("min_range") = 0.0, py::arg("discretize") = false, py::arg("threads") = 0u,
           py::arg("region") = py::none())
      .def("trace_scan", &traceScan, py::arg("points"), py::arg("origin"),
           py::arg("orientation") = py::none(), py::kw_only(), py::arg("max_range") = -1.0,
           py::arg("min_range") = 0.0, py::arg("discretize") = false, py::arg("threads") = 0u)
      .def("apply_scan", &applyScan, py::arg("blocks"), py::kw_only(), py::arg("region") = py::none())
      .def_static("block_keys", &blockKeys, py::arg("blocks"))
      .def(
          "point_keys",
          [](const FastOctTree& t, const py::handle& points) {
            const Points p = toPoints(points, "points");
            const std::size_t n = std::size_t(p.shape(0));
            py::array_t<std::int32_t> keys = newArray<std::int32_t>(n, 3);
            std::int32_t* k = keys.mutable_data();
            for (std::size_t i = 0; i < n; ++i) {
              const float* q = p.data() + 3 * i;
              Key key;
              if (!t.getGrid().pointToKey(q[0], q[1], q[2], key))
                throw py::value_error("points: row " + std::to_string(i) +
                                      " is not finite or lies beyond the key range");
              k[3 * i] = key.x, k[3 * i + 1] = key.y, k[3 * i + 2] = key.z;
            }
            return keys;
          },
          py::arg("points"))
      .def(
          "get_log_odds",
          [](const FastOctTree& t, const py::handle& keys) {
            return perKey<float>(keys, [&](const Key& k) { return t.getLogOdds(k); });
          },
          py::arg("keys"))
      .def(
          "get_state",
          [](const FastOctTree& t, const py::handle& keys) {
            return perKey<std::uint8_t>(keys, [&](const Key& k) { return std::uint8_t(t.getCell(k)); });
          },
          py::arg("keys"))
      .def("cells", &cells)
      .def("occupied_centers", &occupiedCenters)
      .def_property_readonly("occupied_count", &FastOctTree::getOccupiedCount)
      .def_property_readonly("free_count", &FastOctTree::getFreeCount)
      .def_property_readonly("node_count", &FastOctTree::getNodeCount)
      .def_property_readonly("memory_bytes", &FastOctTree::getMemoryBytes)
      .def_property_readonly("empty", &FastOctTree::empty)
      .def("merge", &FastOctTree::merge, py::arg("other"), py::call_guard<py::gil_scoped_release>())
      .def("save", &save, py::arg("path"), py::call_guard<py::gil_scoped_release>())
      .def_static("load", &load, py::arg("path"), py::call_guard<py::gil_scoped_release>());

  m.def(
      "psi",
      [](const FastOctTree& a, const FastOctTree& b, bool include_free, const py::object& cap,
         unsigned threads) {
        pcl::fot::PsiOptions options;
        options.include_free = include_free;
        options.threads = threads;
        if (!cap.is_none()) {
          const std::int64_t c = cap.cast<std::int64_t>();
          if (c < 0) throw py::value_error("cap must not be negative");
          options.cap = c;
        }
        pcl::fot::PsiResult r;
        {
          py::gil_scoped_release unlocked;
          r = pcl::fot::psi(a, b, options);
        }
        py::dict d;
        d["sum"] = r.sum;
        d["cells"] = r.cells;
        d["defined"] = r.defined;
        d["mean"] = r.mean();
        d["metres"] = r.metres();
        return d;
      },
      py::arg("a"), py::arg("b"), py::kw_only(), py::arg("include_free") = false, py::arg("cap") = py::none(),
      py::arg("threads") = 1u);
}

}  // namespace pcl_fot_python
