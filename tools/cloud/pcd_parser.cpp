#include <string>
#include <vector>

#include "cloud_parser.h"
#include "cloud_values.h"

namespace fot_tools {
namespace {

using namespace cloud_values;

struct Field {
  std::string name;
  ValueType type;
  std::uint64_t count = 1;
  std::uint64_t offset = 0;  // in a point (binary), or in its field's block (binary_compressed)
};

enum class Layout { Ascii, Binary, Compressed };

struct Header {
  std::vector<Field> fields;
  std::uint64_t width = 0, height = 0, points = 0;
  Layout layout = Layout::Ascii;
  std::uint64_t point_bytes = 0, values = 0;  // of one point
  std::size_t axes[3] = {0, 0, 0};            // the fields of x, y and z
  float origin[3] = {0, 0, 0};
  float orientation[4] = {1, 0, 0, 0};
};

/** The header's value for each field on a SIZE, TYPE or COUNT line. */
template <typename Set>
void perField(const std::vector<std::string>& w, std::vector<Field>& fields, Set&& set) {
  if (fields.empty() || w.size() - 1 != fields.size())
    damaged("its " + w[0] + " line does not give one value for each of its FIELDS");
  for (std::size_t i = 0; i < fields.size(); ++i) set(w[i + 1], fields[i]);
}

/** The layout checks that come once the header is whole. */
void settle(Header& h, bool has_points) {
  if (h.fields.empty()) damaged("its PCD header has no FIELDS line");
  for (Field& f : h.fields) {
    if (!isValid(f.type))
      damaged("its field '" + f.name + "' has SIZE " + std::to_string(f.type.size) + " and TYPE " +
              std::string(1, f.type.kind) + ", which no number has");
    f.offset = h.point_bytes;
    h.point_bytes += times(f.type.size, f.count);
    h.values += f.count;
    if (h.point_bytes > std::numeric_limits<std::uint32_t>::max() || h.values > (1u << 24))
      damaged("its points are larger than any PCD point");
  }
  // PCL's defaults for older files: no size at all is an unorganised cloud of POINTS points.
  if (h.height == 0) {
    h.height = 1;
    if (h.width == 0) h.width = h.points;
  }
  if (!has_points) h.points = times(h.width, h.height);
  if (h.width > std::numeric_limits<std::uint32_t>::max() ||
      h.height > std::numeric_limits<std::uint32_t>::max() || times(h.width, h.height) != h.points)
    damaged("its WIDTH times HEIGHT is not its POINTS");
  for (int a = 0; a < 3; ++a) {
    std::size_t i = 0;
    while (i < h.fields.size() &&
           !(h.fields[i].count > 0 && h.fields[i].name == std::string(1, char('x' + a))))
      ++i;
    if (i == h.fields.size()) throw CloudFileError("has no x, y, z fields");
    if (h.fields[i].type.kind != 'F')
      throw CloudFileError("stores " + h.fields[i].name + " as an integer; float or double needed");
    h.axes[a] = i;
  }
}

Header readHeader(Cursor& in) {
  Header h;
  bool has_points = false;
  std::vector<std::string> w;
  while (in.headerLine(w)) {
    if (w.empty() || w[0][0] == '#' || w[0] == "VERSION") continue;
    const std::string& key = w[0];
    if (key == "FIELDS" || key == "COLUMNS") {
      h.fields.assign(w.size() - 1, Field());
      for (std::size_t i = 1; i < w.size(); ++i) h.fields[i - 1].name = w[i];
    } else if (key == "SIZE") {
      perField(w, h.fields, [](const std::string& v, Field& f) {
        std::uint64_t size;
        if (!countValue(v, size) || size > 8) damaged("its SIZE line holds '" + v + "'");
        f.type.size = unsigned(size);
      });
    } else if (key == "TYPE") {
      perField(w, h.fields, [](const std::string& v, Field& f) { f.type.kind = v.size() == 1 ? v[0] : '?'; });
    } else if (key == "COUNT") {
      perField(w, h.fields, [](const std::string& v, Field& f) {
        if (!countValue(v, f.count)) damaged("its COUNT line holds '" + v + "'");
      });
    } else if (key == "WIDTH" || key == "HEIGHT" || key == "POINTS") {
      std::uint64_t& v = key == "WIDTH" ? h.width : key == "HEIGHT" ? h.height : h.points;
      if (w.size() != 2 || !countValue(w[1], v)) damaged("its " + key + " line is not one count");
      has_points = has_points || key == "POINTS";
    } else if (key == "VIEWPOINT") {
      double v[7];
      for (int i = 0; i < 7; ++i)
        if (w.size() != 8 || !textValue(w[i + 1].data(), w[i + 1].data() + w[i + 1].size(), v[i]))
          damaged("its VIEWPOINT line is not 7 numbers");
      for (int i = 0; i < 3; ++i) h.origin[i] = toFloat(v[i]);
      for (int i = 0; i < 4; ++i) h.orientation[i] = toFloat(v[3 + i]);
    } else if (key == "DATA" && w.size() == 2 &&
               (w[1] == "ascii" || w[1] == "binary" || w[1] == "binary_compressed")) {
      h.layout = w[1] == "ascii" ? Layout::Ascii : w[1] == "binary" ? Layout::Binary : Layout::Compressed;
      settle(h, has_points);
      return h;
    } else {
      damaged(
          "its PCD header has a line that is none of FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT, VIEWPOINT, "
          "POINTS and DATA ascii, binary or binary_compressed");
    }
  }
  damaged("its PCD header has no DATA line");
}

[[noreturn]] void claimsTooMuch(std::size_t file_size) {
  damaged("its header claims more points than its " + std::to_string(file_size) + " bytes hold");
}

/**
 * LZF, as liblzf writes it and PCL's binary_compressed stores it: control bytes below 32 start a run of
 * literal bytes, the others copy earlier output. Exactly out_size bytes, or false.
 */
bool lzfDecode(const unsigned char* in, std::size_t in_size, unsigned char* out, std::size_t out_size) {
  std::size_t i = 0, o = 0;
  while (i < in_size) {
    const std::size_t control = in[i++];
    if (control < 32) {
      const std::size_t n = control + 1;
      if (n > in_size - i || n > out_size - o) return false;
      std::memcpy(out + o, in + i, n);
      i += n, o += n;
      continue;
    }
    std::size_t n = control >> 5;
    if (n == 7) {
      if (i == in_size) return false;
      n += in[i++];
    }
    n += 2;
    if (i == in_size) return false;
    const std::size_t back = ((control & 0x1f) << 8) + in[i++] + 1;
    if (back > o || n > out_size - o) return false;
    for (const std::size_t stop = o + n; o < stop; ++o)
      out[o] = out[o - back];  // the copy may overlap itself
  }
  return o == out_size;
}

void readBinary(Cursor& in, const Header& h, std::size_t file_size, std::vector<float>& xyz) {
  const unsigned char* data = in.take(times(h.points, h.point_bytes));
  if (!data) claimsTooMuch(file_size);
  xyz.resize(3 * h.points);
  float* out = xyz.data();
  for (std::uint64_t i = 0; i < h.points; ++i, data += h.point_bytes)
    for (std::size_t a : h.axes)
      *out++ = toFloat(binaryValue(data + h.fields[a].offset, h.fields[a].type, false));
}

/** binary_compressed: the sizes, then LZF of the fields one after the other, each for every point. */
void readCompressed(Cursor& in, const Header& h, std::size_t file_size, std::vector<float>& xyz) {
  if (h.points == 0) return;
  const unsigned char* sizes = in.take(8);
  if (!sizes) damaged("its compressed data has no sizes");
  const std::uint64_t packed = std::uint64_t(binaryValue(sizes, ValueType{'U', 4}, false)),
                      unpacked = std::uint64_t(binaryValue(sizes + 4, ValueType{'U', 4}, false));
  const std::uint64_t expected = times(h.points, h.point_bytes);
  const unsigned char* data = in.take(packed);
  // LZF makes at most 88 bytes of 3 (a back reference of 264), so no allocation is larger.
  if (!data || expected > times(packed, 88)) claimsTooMuch(file_size);
  if (unpacked != expected) damaged("its compressed data does not unpack to its points");
  std::vector<unsigned char> fields(expected);
  if (!lzfDecode(data, packed, fields.data(), fields.size()))
    damaged("its compressed data does not unpack to its points");
  xyz.resize(3 * h.points);
  for (int a = 0; a < 3; ++a) {
    const Field& f = h.fields[h.axes[a]];
    const unsigned char* block = fields.data() + times(f.offset, h.points);
    const std::uint64_t step = times(f.type.size, f.count);
    for (std::uint64_t i = 0; i < h.points; ++i)
      xyz[3 * i + a] = toFloat(binaryValue(block + i * step, f.type, false));
  }
}

/** ascii: every value as text, in field order; only x, y, z are parsed. */
void readAscii(Cursor& in, const Header& h, std::size_t file_size, std::vector<float>& xyz) {
  // A value takes a character and a separator, bar the last.
  if (h.points > 0 && times(h.points, 2 * h.values) - 1 > in.left()) claimsTooMuch(file_size);
  xyz.resize(3 * h.points);
  for (std::uint64_t i = 0; i < h.points; ++i)
    for (std::size_t field = 0; field < h.fields.size(); ++field)
      for (std::uint64_t k = 0; k < h.fields[field].count; ++k) {
        const char *first, *last;
        if (!in.word(first, last))
          damaged("it ends at point " + std::to_string(i) + " of " + std::to_string(h.points));
        if (k != 0) continue;
        for (int a = 0; a < 3; ++a) {
          if (field != h.axes[a]) continue;
          double v;
          if (!textValue(first, last, v))
            damaged("point " + std::to_string(i) + " has a " + h.fields[field].name +
                    " that is not a number");
          xyz[3 * i + a] = toFloat(v);
        }
      }
}

}  // namespace

XyzCloud parsePcd(const char* bytes, std::size_t size) {
  Cursor in(bytes, size);
  const Header h = readHeader(in);
  XyzCloud cloud;
  cloud.width = std::uint32_t(h.width);
  cloud.height = std::uint32_t(h.height);
  std::copy(h.origin, h.origin + 3, cloud.origin);
  std::copy(h.orientation, h.orientation + 4, cloud.orientation);
  // Each layout checks that its data can hold the points before it allocates for them.
  if (h.layout == Layout::Binary) readBinary(in, h, size, cloud.xyz);
  if (h.layout == Layout::Compressed) readCompressed(in, h, size, cloud.xyz);
  if (h.layout == Layout::Ascii) readAscii(in, h, size, cloud.xyz);
  return cloud;
}

}  // namespace fot_tools
