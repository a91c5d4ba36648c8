#include "arrays.h"

#include <cmath>
#include <limits>

namespace pcl_fot_python {
namespace {

void checkRows(const py::array& a, const char* what) {
  if (a.ndim() == 2 && a.shape(1) == 3) return;
  std::string shape;
  for (py::ssize_t i = 0; i < a.ndim(); ++i) shape += (i ? ", " : "") + std::to_string(a.shape(i));
  throw py::value_error(std::string(what) + " must be an (N, 3) array, not one of shape (" + shape + ")");
}

}  // namespace

Points toPoints(const py::handle& obj, const char* what) {
  const py::array a = py::array::ensure(obj);
  if (!a) throw py::type_error(std::string(what) + " must be a numpy array of float32 or float64");
  if (!a.dtype().is(py::dtype::of<float>()) && !a.dtype().is(py::dtype::of<double>()))
    throw py::type_error(std::string(what) + " must hold float32 or float64, not " +
                         std::string(py::str(a.dtype())));
  checkRows(a, what);
  return Points::ensure(a);  // no copy for contiguous float32
}

Keys toKeys(const py::handle& obj, const char* what) {
  const py::array a = py::array::ensure(obj);
  if (!a || a.dtype().kind() != 'i')
    throw py::type_error(std::string(what) + " must be a numpy array of signed integers");
  checkRows(a, what);
  if (a.itemsize() > 4) {
    const py::array_t<std::int64_t, py::array::c_style> wide =
        py::array_t<std::int64_t, py::array::c_style>::ensure(a);
    const std::int64_t* v = wide.data();
    for (py::ssize_t i = 0; i < wide.size(); ++i)
      if (v[i] < std::numeric_limits<std::int32_t>::min() || v[i] > std::numeric_limits<std::int32_t>::max())
        throw py::value_error(std::string(what) + " holds a key beyond int32");
  }
  return Keys::ensure(a);
}

std::array<double, 3> toTriple(const py::handle& obj, const char* what) {
  const py::array_t<double, py::array::c_style | py::array::forcecast> a =
      py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
  if (!a || a.size() != 3) throw py::value_error(std::string(what) + " must be three numbers");
  const std::array<double, 3> t{a.data()[0], a.data()[1], a.data()[2]};
  for (const double v : t)
    if (!std::isfinite(v)) throw py::value_error(std::string(what) + " must be finite");
  return t;
}

}  // namespace pcl_fot_python
