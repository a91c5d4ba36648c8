#include <limits>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "cloud_parser.h"
#include "cloud_values.h"

namespace fot_tools {
namespace {

using namespace cloud_values;

struct Property {
  std::string name;
  ValueType type;
  bool list = false;
  ValueType count_type;  // of a list
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
};

enum class Format { Ascii, LittleEndian, BigEndian };

struct Header {
  Format format = Format::Ascii;
  std::vector<Element> elements;
  std::uint64_t columns = 0, rows = 0;  // obj_info num_cols, num_rows
  double offset[3] = {0, 0, 0};  // obj_info echo_rgb_offset_x, _y, _z: PCL's sensor origin without a camera
};

bool typeNamed(const std::string& name, ValueType& t) {
  static const struct {
    const char* name;
    ValueType type;
  } kTypes[] = {{"char", {'I', 1}},  {"int8", {'I', 1}},    {"uchar", {'U', 1}},  {"uint8", {'U', 1}},
                {"short", {'I', 2}}, {"int16", {'I', 2}},   {"ushort", {'U', 2}}, {"uint16", {'U', 2}},
                {"int", {'I', 4}},   {"int32", {'I', 4}},   {"uint", {'U', 4}},   {"uint32", {'U', 4}},
                {"float", {'F', 4}}, {"float32", {'F', 4}}, {"double", {'F', 8}}, {"float64", {'F', 8}}};
  for (const auto& k : kTypes)
    if (name == k.name) {
      t = k.type;
      return true;
    }
  return false;
}

Header readHeader(Cursor& in) {
  std::vector<std::string> w;
  if (!in.headerLine(w) || w.size() != 1 || w[0] != "ply")
    throw CloudFileError("is not a PLY file: it does not start with 'ply'");
  Header h;
  bool has_format = false;
  while (in.headerLine(w)) {
    if (w.empty() || w[0] == "comment") continue;
    if (w[0] == "format" && w.size() == 3 &&
        (w[1] == "ascii" || w[1] == "binary_little_endian" || w[1] == "binary_big_endian")) {
      h.format = w[1] == "ascii"                  ? Format::Ascii
                 : w[1] == "binary_little_endian" ? Format::LittleEndian
                                                  : Format::BigEndian;
      has_format = true;
    } else if (w[0] == "obj_info") {
      if (w.size() == 3 && (w[1] == "num_cols" || w[1] == "num_rows") &&
          !countValue(w[2], w[1] == "num_cols" ? h.columns : h.rows))
        damaged("its obj_info " + w[1] + " is not a count");
      for (int a = 0; a < 3; ++a)
        if (w.size() == 3 && w[1] == std::string("echo_rgb_offset_") + char('x' + a) &&
            !textValue(w[2].data(), w[2].data() + w[2].size(), h.offset[a]))
          damaged("its obj_info " + w[1] + " is not a number");
    } else if (w[0] == "element" && w.size() == 3) {
      h.elements.emplace_back();
      h.elements.back().name = w[1];
      if (!countValue(w[2], h.elements.back().count)) damaged("its element " + w[1] + " has no count");
    } else if (w[0] == "property" && !h.elements.empty() &&
               (w.size() == 3 || (w.size() == 5 && w[1] == "list"))) {
      Property p;
      p.list = w.size() == 5;
      p.name = w.back();
      if (!typeNamed(w[p.list ? 3 : 1], p.type) || (p.list && !typeNamed(w[2], p.count_type)) ||
          (p.list && p.count_type.kind == 'F'))
        damaged("its property " + p.name + " has a type PLY does not have");
      h.elements.back().properties.push_back(p);
    } else if (w[0] == "end_header") {
      if (!has_format) damaged("its PLY header has no format line");
      return h;
    } else {
      damaged(
          "its PLY header has a line that is none of format, comment, obj_info, element, property and "
          "end_header");
    }
  }
  damaged("its PLY header has no end_header line");
}

/** Reads the body's values in order, whatever the format. */
class Values {
 public:
  Values(Cursor& in, Format format, std::size_t file_size)
      : in_(in), format_(format), file_size_(file_size) {}

  double next(ValueType t) {
    if (format_ != Format::Ascii) {
      const unsigned char* p = in_.take(t.size);
      if (!p) ends();
      return binaryValue(p, t, format_ == Format::BigEndian);
    }
    const char *first, *last;
    double v;
    if (!in_.word(first, last)) ends();
    if (!textValue(first, last, v)) damaged("its data holds a word that is not a number");
    return v;
  }

  /** A list's length: a whole number that the rest of the file can hold. */
  std::uint64_t length(ValueType t, ValueType item) {
    const double n = next(t);
    if (!(n >= 0 && n == std::floor(n) && n < 1e18) || times(std::uint64_t(n), minBytes(item)) > in_.left())
      damaged("its data holds a list longer than the file");
    return std::uint64_t(n);
  }

  /** The fewest bytes a value of type t takes: its size, or in text a character and a separator. */
  unsigned minBytes(ValueType t) const { return format_ == Format::Ascii ? 2 : t.size; }
  /** The same for an element's items, over their properties (a list holds at least its length). */
  std::uint64_t minBytes(const Element& e) const {
    std::uint64_t bytes = 0;
    for (const Property& p : e.properties) bytes += minBytes(p.list ? p.count_type : p.type);
    return bytes;
  }
  /** Throws unless the rest of the file can hold the element's items. */
  void require(const Element& e) const {
    const std::uint64_t bytes = times(e.count, minBytes(e));
    if (bytes > in_.left() + (format_ == Format::Ascii ? 1 : 0))  // the last value needs no separator
      damaged("its header claims more points than its " + std::to_string(file_size_) + " bytes hold");
  }

 private:
  [[noreturn]] void ends() const { damaged("its data ends before its header's elements do"); }

  Cursor& in_;
  Format format_;
  std::size_t file_size_;
};

/** The property named `name` of e, which must hold one float or double; -1 if e has none. */
int scalarNamed(const Element& e, const std::string& name) {
  for (std::size_t i = 0; i < e.properties.size(); ++i) {
    const Property& p = e.properties[i];
    if (p.name != name) continue;
    if (p.list) return -1;
    if (p.type.kind != 'F') throw CloudFileError("stores " + name + " as an integer; float or double needed");
    return int(i);
  }
  return -1;
}

/** What the camera element PCL writes gives: the sensor pose (axes as the rows of its rotation) and size. */
struct Camera {
  double values[14] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0};
  bool has_pose = false;
  static int slot(const std::string& name) {
    static const char* const kNames[] = {"view_px", "view_py", "view_pz",   "x_axisx",  "x_axisy",
                                         "x_axisz", "y_axisx", "y_axisy",   "y_axisz",  "z_axisx",
                                         "z_axisy", "z_axisz", "viewportx", "viewporty"};
    for (int i = 0; i < 14; ++i)
      if (name == kNames[i]) return i;
    return -1;
  }
};

/** What the elements hold that a cloud needs. */
struct Body {
  std::vector<float> vertices;
  std::uint64_t vertex_count = 0;
  bool has_vertices = false;
  std::vector<std::int64_t> grid;  // range_grid: each cell's vertex, or -1
  bool has_grid = false;
  Camera camera;
};

/** Reads every element's items: the first vertex, range_grid and camera elements are kept. */
Body readElements(Cursor& in, const Header& h, std::size_t size) {
  Values values(in, h.format, size);
  Body b;
  for (const Element& e : h.elements) {
    if (e.properties.empty()) continue;  // its items hold nothing
    values.require(e);
    const bool is_vertex = e.name == "vertex" && !b.has_vertices,
               is_grid = e.name == "range_grid" && !b.has_grid,
               is_camera = e.name == "camera" && !b.camera.has_pose;
    int axis[3] = {-1, -1, -1};
    if (is_vertex) {
      for (int a = 0; a < 3; ++a) axis[a] = scalarNamed(e, std::string(1, char('x' + a)));
      if (axis[0] < 0 || axis[1] < 0 || axis[2] < 0) throw CloudFileError("has no x, y, z fields");
      b.vertices.resize(3 * e.count);
      b.vertex_count = e.count;
      b.has_vertices = true;
    }
    if (is_grid) b.grid.assign(e.count, -1);
    for (std::uint64_t item = 0; item < e.count; ++item)
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        const Property& p = e.properties[k];
        if (p.list) {
          const std::uint64_t n = values.length(p.count_type, p.type);
          for (std::uint64_t j = 0; j < n; ++j) {
            const double v = values.next(p.type);
            if (is_grid && j == 0 && (p.name == "vertex_indices" || p.name == "vertex_index"))
              b.grid[item] =
                  v >= 0 && v < double(std::numeric_limits<std::int64_t>::max()) ? std::int64_t(v) : -2;
          }
          continue;
        }
        const double v = values.next(p.type);
        if (is_vertex)
          for (int a = 0; a < 3; ++a)
            if (axis[a] == int(k)) b.vertices[3 * item + a] = toFloat(v);
        if (is_camera && item == 0 && Camera::slot(p.name) >= 0) b.camera.values[Camera::slot(p.name)] = v;
      }
    b.has_grid = b.has_grid || is_grid;
    b.camera.has_pose = b.camera.has_pose || is_camera;
  }
  if (!b.has_vertices) throw CloudFileError("has no x, y, z fields");
  return b;
}

/** The cloud the elements describe: organised by the camera, obj_info or range_grid, posed by the camera. */
XyzCloud assembleCloud(const Header& h, Body& b) {
  XyzCloud cloud;
  const std::uint64_t points = b.has_grid ? b.grid.size() : b.vertex_count;
  if (points > std::numeric_limits<std::uint32_t>::max())
    damaged("it holds more points than a PCL cloud can");
  // The camera's viewportx and viewporty, when they are sizes at all.
  auto dimension = [](double v) { return v >= 0 && v < 1e10 ? std::uint64_t(v) : 0; };
  const Camera& camera = b.camera;
  const std::uint64_t columns = dimension(camera.values[12]), rows = dimension(camera.values[13]);
  if (camera.has_pose && !b.has_grid && times(columns, rows) == points) {
    cloud.width = std::uint32_t(columns), cloud.height = std::uint32_t(rows);
  } else if (times(h.columns, h.rows) == points) {
    cloud.width = std::uint32_t(h.columns), cloud.height = std::uint32_t(h.rows);
  } else {
    cloud.width = std::uint32_t(points), cloud.height = 1;
  }
  if (!b.has_grid) {
    cloud.xyz = std::move(b.vertices);
  } else {
    cloud.xyz.assign(3 * points, std::numeric_limits<float>::quiet_NaN());
    for (std::size_t i = 0; i < b.grid.size(); ++i) {
      if (b.grid[i] == -1) continue;
      if (b.grid[i] < 0 || std::uint64_t(b.grid[i]) >= b.vertex_count)
        damaged("its range_grid names a vertex it does not have");
      std::copy_n(b.vertices.begin() + 3 * b.grid[i], 3, cloud.xyz.begin() + 3 * i);
    }
  }
  for (int i = 0; i < 3; ++i) cloud.origin[i] = toFloat(camera.has_pose ? camera.values[i] : h.offset[i]);
  if (camera.has_pose) {
    Eigen::Matrix3d rotation;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) rotation(r, c) = camera.values[3 + 3 * r + c];
    if (rotation.allFinite()) {
      const Eigen::Quaterniond q(rotation);
      cloud.orientation[0] = float(q.w()), cloud.orientation[1] = float(q.x());
      cloud.orientation[2] = float(q.y()), cloud.orientation[3] = float(q.z());
    }
  }
  return cloud;
}

}  // namespace

XyzCloud parsePly(const char* bytes, std::size_t size) {
  Cursor in(bytes, size);
  const Header h = readHeader(in);
  Body body = readElements(in, h, size);
  return assembleCloud(h, body);
}

}  // namespace fot_tools
