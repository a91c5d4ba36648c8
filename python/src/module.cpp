// The pcl_fot extension module: the library's map, search and ψ on numpy arrays.

#include <cctype>

#include <pcl_fot/tree/fast_oct_tree.h>

#include "bindings.h"

std::string pcl_fot_python::extensionOf(const std::string& path) {
  const std::size_t dot = path.rfind('.');
  std::string e = dot == std::string::npos ? "" : path.substr(dot);
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

PYBIND11_MODULE(_pcl_fot, m) {
  m.doc() = "pcl_fot's FastOctTree, its nearest-neighbour search and psi on numpy arrays.";
  pybind11::register_exception<pcl::fot::MemoryLimitError>(m, "MemoryLimitError", PyExc_MemoryError);
  pcl_fot_python::bindMap(m);
  pcl_fot_python::bindSearch(m);
  pcl_fot_python::bindClouds(m);
}
