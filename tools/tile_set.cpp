#include "tile_set.h"

#include <dirent.h>
#include <sys/stat.h>

#include <cmath>
#include <cstdlib>
#include <utility>
#include <vector>

#include <pcl_fot/io/file_io.h>
#include <pcl_fot/io/fot_file.h>

#include "arguments.h"

namespace fot_tools {
namespace {

constexpr const char* kIndexName = "tiles.json";
constexpr std::size_t kMaxIndexBytes = std::size_t(256) << 20;

/** A JSON value, as much of JSON as the index uses: objects, arrays, numbers, strings, true, false, null. */
struct Json {
  enum class Type { Null, Bool, Number, String, Array, Object } type = Type::Null;
  double number = 0;
  std::string text;
  std::vector<Json> items;
  std::vector<std::pair<std::string, Json>> fields;

  /** The member `name`, which must be there, of the type asked for. */
  const Json& at(const std::string& name, Type wanted) const {
    for (const auto& f : fields)
      if (f.first == name) {
        if (f.second.type != wanted) throw std::invalid_argument("'" + name + "' has the wrong type");
        return f.second;
      }
    throw std::invalid_argument("'" + name + "' is missing");
  }
};

/** A strict reader of one JSON text; nesting deeper than the index's is refused, not recursed into. */
class JsonReader {
 public:
  explicit JsonReader(const std::string& text) : s_(text) {}

  Json document() {
    Json v = value(0);
    space();
    if (i_ != s_.size()) fail("text after the value");
    return v;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw std::invalid_argument("not valid JSON at byte " + std::to_string(i_) + ": " + what);
  }
  void space() {
    while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\n' || s_[i_] == '\r' || s_[i_] == '\t')) ++i_;
  }
  bool take(char c) {
    space();
    if (i_ < s_.size() && s_[i_] == c) return ++i_, true;
    return false;
  }
  void expect(char c) {
    if (!take(c)) fail(std::string("'") + c + "' expected");
  }
  bool word(const char* w) {
    const std::string t(w);
    if (s_.compare(i_, t.size(), t) != 0) return false;
    i_ += t.size();
    return true;
  }

  Json value(int depth) {
    if (depth > 8) fail("nested too deeply");
    space();
    if (i_ == s_.size()) fail("a value expected");
    Json v;
    const char c = s_[i_];
    if (c == '{') {
      v.type = Json::Type::Object;
      ++i_;
      if (take('}')) return v;
      do {
        space();
        Json key = string();
        expect(':');
        v.fields.emplace_back(std::move(key.text), value(depth + 1));
      } while (take(','));
      expect('}');
    } else if (c == '[') {
      v.type = Json::Type::Array;
      ++i_;
      if (take(']')) return v;
      do v.items.push_back(value(depth + 1));
      while (take(','));
      expect(']');
    } else if (c == '"') {
      v = string();
    } else if (word("true")) {
      v.type = Json::Type::Bool;
      v.number = 1;
    } else if (word("false")) {
      v.type = Json::Type::Bool;
    } else if (word("null")) {
      v.type = Json::Type::Null;
    } else {
      const char* begin = s_.c_str() + i_;
      char* end = nullptr;
      v.type = Json::Type::Number;
      v.number = std::strtod(begin, &end);
      if (end == begin || !std::isfinite(v.number)) fail("a value expected");
      i_ += std::size_t(end - begin);
    }
    return v;
  }

  /** A string without escapes other than \" and \\: the index holds file names and words. */
  Json string() {
    if (i_ >= s_.size() || s_[i_] != '"') fail("a string expected");
    Json v;
    v.type = Json::Type::String;
    for (++i_; i_ < s_.size() && s_[i_] != '"'; ++i_) {
      if (s_[i_] == '\\') {
        if (++i_ == s_.size() || (s_[i_] != '"' && s_[i_] != '\\')) fail("an escape the index does not use");
      }
      v.text.push_back(s_[i_]);
    }
    if (i_ == s_.size()) fail("an unterminated string");
    ++i_;
    return v;
  }

  const std::string& s_;
  std::size_t i_ = 0;
};

bool isDirectory(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

std::string indexOf(const std::string& path) {
  return isDirectory(path) ? path + "/" + kIndexName : path;
}

double integer(const Json& v, const std::string& what) {
  if (v.type != Json::Type::Number || v.number != std::floor(v.number) || std::fabs(v.number) > 1e9)
    throw std::invalid_argument(what + " is not an integer");
  return v.number;
}

}  // namespace

bool isTileSet(const std::string& path) {
  const std::string index = indexOf(path);
  return index.size() >= 10 && index.compare(index.size() - 10, 10, kIndexName) == 0;
}

std::vector<std::string> tileSetFiles(const std::string& path) {
  const std::string index = indexOf(path);
  const std::string tiles = index.substr(0, index.find_last_of('/') + 1) + "tiles";
  std::vector<std::string> files{index};
  if (DIR* dir = opendir(tiles.c_str())) {
    while (const dirent* entry = readdir(dir))
      if (entry->d_name[0] != '.') files.push_back(tiles + "/" + entry->d_name);
    closedir(dir);
  }
  return files;
}

pcl::fot::FastOctTree loadTileSet(const std::string& path, std::size_t max_bytes) {
  const std::string index_path = indexOf(path);
  const std::string base = index_path.substr(0, index_path.find_last_of('/') + 1);
  pcl::fot::FastOctTree whole(1.0);
  std::vector<Json> tiles;
  try {
    const std::string text = pcl::fot::io::readFile(index_path, kMaxIndexBytes);
    const Json index = JsonReader(text).document();
    if (index.type != Json::Type::Object || index.at("format", Json::Type::String).text != "pcl_fot tile set")
      throw std::invalid_argument("not a pcl_fot tile set index");
    const Json& origin = index.at("origin", Json::Type::Array);
    const Json& model = index.at("sensor_model", Json::Type::Array);
    if (origin.items.size() != 3 || model.items.size() != 5)
      throw std::invalid_argument("'origin' takes 3 numbers and 'sensor_model' 5");
    double o[3], m[5];
    for (int i = 0; i < 3; ++i) o[i] = origin.items[std::size_t(i)].number;
    for (int i = 0; i < 5; ++i) m[i] = model.items[std::size_t(i)].number;
    whole = pcl::fot::FastOctTree(index.at("resolution", Json::Type::Number).number, o[0], o[1], o[2]);
    whole.setSensorModel(pcl::fot::SensorModel(m[0], m[1], m[2], m[3], m[4]));
    const std::string rule = index.at("rule", Json::Type::String).text;
    if (rule != "log_odds" && rule != "binary") throw std::invalid_argument("unknown rule '" + rule + "'");
    whole.setUpdateRule(rule == "log_odds" ? pcl::fot::UpdateRule::LogOdds : pcl::fot::UpdateRule::Binary);
    whole.setMaxMemoryBytes(max_bytes);
    tiles = index.at("tiles", Json::Type::Array).items;
  } catch (const std::exception& e) {
    throw ToolError(kExitInput, index_path + ": " + e.what());
  }
  for (const Json& tile : tiles) {
    std::string name = "?";
    try {
      if (tile.type != Json::Type::Object) throw std::invalid_argument("not an object");
      name = tile.at("name", Json::Type::String).text;
      const std::string file = tile.at("file", Json::Type::String).text;
      if (file.empty() || file[0] == '/' || file.find("..") != std::string::npos)
        throw std::invalid_argument("its file '" + file + "' lies outside the tile set");
      const double level = integer(tile.at("level", Json::Type::Number), "its level");
      const Json& at = tile.at("index", Json::Type::Array);
      if (level < 2 || level > 15 || at.items.size() != 3)
        throw std::invalid_argument("a bad level or index");
      const pcl::fot::FastOctTree part = pcl::fot::io::loadFot(base + file, max_bytes);
      if (!(part.getGrid() == whole.getGrid())) throw std::invalid_argument("its grid is not the tile set's");
      const std::int64_t edge = std::int64_t(1) << int(level);
      std::int64_t lo[3];
      for (int a = 0; a < 3; ++a) lo[a] = std::int64_t(integer(at.items[std::size_t(a)], "its index")) * edge;
      part.forEachRegion([&](const pcl::fot::Region& r) {
        const std::int64_t k[3] = {r.min_key.x, r.min_key.y, r.min_key.z}, size = std::int64_t(1) << r.level;
        for (int a = 0; a < 3; ++a)
          if (k[a] < lo[a] || k[a] + size > lo[a] + edge)
            throw std::invalid_argument("it holds cells outside its cube");
        return true;
      });
      whole.merge(part);
    } catch (const ToolError&) {
      throw;
    } catch (const pcl::fot::MemoryLimitError&) {
      throw;
    } catch (const std::exception& e) {
      throw ToolError(kExitInput, "tile " + name + " of " + index_path + ": " + e.what());
    }
  }
  return whole;
}

}  // namespace fot_tools
