#pragma once
// Private to the module: each part of the API binds itself into the module.

#include <string>

#include <pybind11/pybind11.h>

namespace pcl_fot_python {

/** A file name's extension, lower case, with the dot: ".pcd"; "" without one. */
std::string extensionOf(const std::string& path);

void bindMap(pybind11::module_& m);
void bindSearch(pybind11::module_& m);
void bindClouds(pybind11::module_& m);

}  // namespace pcl_fot_python
