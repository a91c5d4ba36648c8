#include "io/octomap_format.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "io/region_copy.h"

namespace pcl {
namespace fot {
namespace io {
namespace octomap_format {

std::int32_t cellsFromZero(double origin, double res, const char* axis) {
  const double cells = origin / res;
  const double whole = std::round(cells);
  char text[200];
  if (!(std::abs(whole) <= double(kMaxKey))) {
    std::snprintf(text, sizeof(text), "pcl::fot::io: the map's origin %s = %g lies beyond 2^29 cells from 0",
                  axis, origin);
    throw std::invalid_argument(text);
  }
  if (!(std::abs(cells - whole) <= 1e-6)) {
    std::snprintf(
        text, sizeof(text),
        "pcl::fot::io: OctoMap's voxel boundaries lie on multiples of the resolution, but the map's "
        "origin %s = %.17g is %.9g cells from 0",
        axis, origin, cells);
    throw std::invalid_argument(text);
  }
  return std::int32_t(whole);
}

std::string exactDecimal(double v) {
  for (int digits = 6; digits <= 17; ++digits) {
    std::ostringstream s;
    s.precision(digits);
    s << v;
    if (std::stod(s.str()) == v) return s.str();
  }
  return std::to_string(v);
}

std::string headerText(const char* first_line, std::uint64_t size, double res) {
  return std::string(first_line) +
         "\n# (feel free to add / change comments, but leave the first line as it is!)\n#\nid OcTree\nsize " +
         std::to_string(size) + "\nres " + exactDecimal(res) + "\ndata\n";
}

Header readHeader(const char* bytes, std::size_t size, const char* first_line, const std::string& what_file) {
  auto fail = [&](const std::string& what) { return FormatError(what_file + ": " + what); };
  std::size_t at = 0;
  auto line = [&](std::string& out) {
    const std::size_t limit = std::min(size, at + 1024);
    std::size_t end = at;
    while (end < limit && bytes[end] != '\n') ++end;
    if (end == limit) throw fail("the header is truncated or has an overlong line");
    out.assign(bytes + at, end - at);
    if (!out.empty() && out.back() == '\r') out.pop_back();
    at = end + 1;
  };
  std::string text;
  line(text);
  if (text.compare(0, std::string(first_line).size(), first_line) != 0)
    throw fail("it does not start with '" + std::string(first_line) + "'");
  Header h{"", 0, std::numeric_limits<double>::quiet_NaN(), 0};
  bool has_size = false;
  for (int lines = 0;; ++lines) {
    if (lines > 1000) throw fail("the header has no 'data' line");
    line(text);
    std::istringstream fields(text);
    std::string key;
    fields >> key;
    if (key.empty() || key[0] == '#') continue;
    if (key == "data") break;
    if (key == "id") {
      fields >> h.id;
    } else if (key == "size") {
      if (!(fields >> h.size)) throw fail("the size is not a number");
      has_size = true;
    } else if (key == "res") {
      if (!(fields >> h.resolution)) throw fail("the resolution is not a number");
    }
  }
  if (h.id == "1") h.id = "OcTree";  // OctoMap's legacy id
  if (h.id.empty()) throw fail("the header has no tree type (id)");
  if (!has_size) throw fail("the header has no size");
  const std::string bad_grid = CellGrid::whyInvalid(h.resolution, 0.0, 0.0, 0.0);
  if (!bad_grid.empty()) throw fail(bad_grid);
  h.body = at;
  return h;
}

FastOctTree const* toStaging(const FastOctTree& tree, std::optional<FastOctTree>& moved,
                             std::size_t max_pool_bytes) {
  const CellGrid& grid = tree.getGrid();
  const double res = grid.resolution();
  const std::int64_t shift_to_octomap[3] = {kCentre + cellsFromZero(grid.origin()[0], res, "x"),
                                            kCentre + cellsFromZero(grid.origin()[1], res, "y"),
                                            kCentre + cellsFromZero(grid.origin()[2], res, "z")};
  tree.forEachRegion([&](const Region& r) {
    const std::int64_t last = (std::int64_t(1) << r.level) - 1;
    const std::int64_t k[3] = {r.min_key.x, r.min_key.y, r.min_key.z};
    for (int a = 0; a < 3; ++a)
      if (k[a] + shift_to_octomap[a] < 0 || k[a] + last + shift_to_octomap[a] > 65535)
        throw std::invalid_argument(
            "pcl::fot::io: the map has cells beyond OctoMap's 65536 cells per axis (" +
            std::to_string(kCentre) + " cells either side of coordinate 0)");
  });
  // Staging keys are OctoMap keys less 32768, those of the map itself at origin 0: then no copy is needed.
  if (shift_to_octomap[0] == kCentre && shift_to_octomap[1] == kCentre && shift_to_octomap[2] == kCentre)
    return &tree;
  const std::int64_t shift[3] = {shift_to_octomap[0] - kCentre, shift_to_octomap[1] - kCentre,
                                 shift_to_octomap[2] - kCentre};
  moved.emplace(shiftedCopy(tree, CellGrid(res), shift, max_pool_bytes));
  return &*moved;
}

FastOctTree placeStaging(FastOctTree staging, double res, const OctoMapImportOptions& options) {
  const std::int32_t origin_cells[3] = {cellsFromZero(options.origin[0], res, "x"),
                                        cellsFromZero(options.origin[1], res, "y"),
                                        cellsFromZero(options.origin[2], res, "z")};
  // At origin 0 the staging tree is the map; elsewhere its keys move by the origin's cells.
  if (origin_cells[0] == 0 && origin_cells[1] == 0 && origin_cells[2] == 0) {
    staging.setMaxMemoryBytes(std::numeric_limits<std::size_t>::max());
    return staging;
  }
  const std::int64_t shift[3] = {-std::int64_t(origin_cells[0]), -std::int64_t(origin_cells[1]),
                                 -std::int64_t(origin_cells[2])};
  return shiftedCopy(staging, CellGrid(res, options.origin[0], options.origin[1], options.origin[2]), shift,
                     options.max_pool_bytes);
}

}  // namespace octomap_format
}  // namespace io
}  // namespace fot
}  // namespace pcl
