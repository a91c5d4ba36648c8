// The nearest-neighbour search on a point array, with in-place updates.

#include <cmath>
#include <limits>
#include <vector>

#include <pcl_fot/search/point_index.h>

#include "arrays.h"
#include "bindings.h"

namespace pcl_fot_python {
namespace {

/**
 * A pcl::fot::PointIndex of an (N, 3) array: points are numbered 0 to N - 1, and added points get the
 * numbers after the highest given so far. Distances are squared Euclidean, as PCL's searches report them.
 */
class PointSearch {
 public:
  PointSearch(const py::object& points, const py::object& resolution)
      : index_(resolution.is_none() ? pcl::fot::PointIndex()
                                    : pcl::fot::PointIndex(resolution.cast<double>())) {
    if (points.is_none()) return;
    const Points p = toPoints(points, "points");
    py::gil_scoped_release unlocked;
    index_.build(p.data(), std::size_t(p.shape(0)), 3 * sizeof(float));
    next_ = std::int32_t(p.shape(0));
  }

  py::tuple knn(const py::handle& queries, std::size_t k) const {
    if (k == 0) throw py::value_error("k must be positive");
    const Points q = toPoints(queries, "queries");
    const std::size_t n = std::size_t(q.shape(0));
    py::array_t<std::int32_t> indices = newArray<std::int32_t>(n, k);
    py::array_t<float> distances = newArray<float>(n, k);
    std::int32_t* out_i = indices.mutable_data();
    float* out_d = distances.mutable_data();
    {
      py::gil_scoped_release unlocked;
      std::vector<std::int32_t> found;
      std::vector<float> d;
      for (std::size_t i = 0; i < n; ++i) {
        const std::size_t m = index_.nearestK(q.data() + 3 * i, k, pcl::fot::Metric::Euclidean, found, d);
        for (std::size_t j = 0; j < k; ++j) {  // fewer than k points: -1 and inf fill the row
          out_i[i * k + j] = j < m ? found[j] : -1;
          out_d[i * k + j] = j < m ? d[j] : std::numeric_limits<float>::infinity();
        }
      }
    }
    return py::make_tuple(indices, distances);
  }

  py::tuple radius(const py::handle& query, double r, std::size_t max_nn) const {
    if (!(r >= 0.0) || !std::isfinite(r)) throw py::value_error("radius must be finite and not negative");
    const std::array<double, 3> q = toTriple(query, "query");
    const float p[3] = {float(q[0]), float(q[1]), float(q[2])};
    std::vector<std::int32_t> found;
    std::vector<float> d;
    {
      py::gil_scoped_release unlocked;
      index_.radiusSearch(p, r, pcl::fot::Metric::Euclidean, found, d, max_nn);
    }
    return py::make_tuple(toArray(found), toArray(d));
  }

  /** The numbers of the points added; -1 for those left out (not finite). */
  py::array_t<std::int32_t> add(const py::handle& points) {
    const Points p = toPoints(points, "points");
    const std::size_t n = std::size_t(p.shape(0));
    if (std::int64_t(next_) + std::int64_t(n) > std::numeric_limits<std::int32_t>::max())
      throw py::value_error("add: the points' numbers would pass INT32_MAX");
    {
      py::gil_scoped_release unlocked;
      index_.add(p.data(), n, 3 * sizeof(float), next_);
    }
    py::array_t<std::int32_t> numbers = newArray<std::int32_t>(n);
    for (std::size_t i = 0; i < n; ++i) {
      const float* x = p.data() + 3 * i;
      const bool finite = std::isfinite(x[0]) && std::isfinite(x[1]) && std::isfinite(x[2]);
      numbers.mutable_data()[i] = finite ? next_ + std::int32_t(i) : -1;
    }
    next_ += std::int32_t(n);
    return numbers;
  }

  std::size_t remove(const py::handle& numbers) {
    const py::array_t<std::int32_t, py::array::c_style | py::array::forcecast> a =
        py::array_t<std::int32_t, py::array::c_style | py::array::forcecast>::ensure(numbers);
    if (!a || a.ndim() != 1) throw py::value_error("remove takes a one-dimensional array of point numbers");
    py::gil_scoped_release unlocked;
    return index_.remove(a.data(), std::size_t(a.size()));
  }

  std::size_t size() const { return index_.size(); }
  std::size_t memoryBytes() const { return index_.getMemoryBytes(); }
  double resolution() const { return index_.resolution(); }

 private:
  pcl::fot::PointIndex index_;
  std::int32_t next_ = 0;
};

}  // namespace

void bindSearch(py::module_& m) {
  py::class_<PointSearch>(
      m, "FastOctTreeSearch",
      "Exact k-NN and radius search on an (N, 3) point array, with in-place add and remove.")
      .def(py::init<const py::object&, const py::object&>(), py::arg("points") = py::none(),
           py::arg("resolution") = py::none())
      .def("knn", &PointSearch::knn, py::arg("queries"), py::arg("k"))
      .def("radius", &PointSearch::radius, py::arg("query"), py::arg("radius"), py::arg("max_nn") = 0)
      .def("add", &PointSearch::add, py::arg("points"))
      .def("remove", &PointSearch::remove, py::arg("numbers"))
      .def_property_readonly("size", &PointSearch::size)
      .def_property_readonly("memory_bytes", &PointSearch::memoryBytes)
      .def_property_readonly("resolution", &PointSearch::resolution);
}

}  // namespace pcl_fot_python
