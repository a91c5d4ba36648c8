#pragma once
// Private to the module: numpy arrays in and out, checked, and copied only where they must be.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

namespace pcl_fot_python {

namespace py = pybind11;

/** Float points as the library reads them: float32, rows of x, y, z, contiguous. */
using Points = py::array_t<float, py::array::c_style | py::array::forcecast>;
/** Integer cell keys, rows of x, y, z. */
using Keys = py::array_t<std::int32_t, py::array::c_style | py::array::forcecast>;

/**
 * An (N, 3) array of float32 or float64 points as contiguous float32: the array itself when it is one
 * already, a converted copy otherwise. Throws TypeError for another dtype and ValueError for another shape.
 */
Points toPoints(const py::handle& obj, const char* what);
/** An (N, 3) array of integer keys as contiguous int32; keys beyond int32 are refused with ValueError. */
Keys toKeys(const py::handle& obj, const char* what);
/** Three finite numbers, as a sequence or an array. */
std::array<double, 3> toTriple(const py::handle& obj, const char* what);

/** A new (rows, columns) array of T, C order; columns 0 makes it one-dimensional. */
template <typename T>
py::array_t<T> newArray(std::size_t rows, std::size_t columns = 0) {
  if (columns == 0) return py::array_t<T>(py::ssize_t(rows));
  return py::array_t<T>({py::ssize_t(rows), py::ssize_t(columns)});
}

/** A one-dimensional array holding a copy of the vector. */
template <typename T>
py::array_t<T> toArray(const std::vector<T>& v) {
  py::array_t<T> out = newArray<T>(v.size());
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

}  // namespace pcl_fot_python
