#include "tile_index.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <utility>

namespace fot_tools {
namespace {

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
      v.type = Json::Type::Number;
      v.number = number();
    }
    return v;
  }

  /** JSON's number grammar, checked before strtod, which would also take hex, "inf", "nan" and "1.". */
  double number() {
    const std::size_t start = i_;
    const auto digits = [&] {
      const std::size_t from = i_;
      while (i_ < s_.size() && s_[i_] >= '0' && s_[i_] <= '9') ++i_;
      return i_ - from;
    };
    if (i_ < s_.size() && s_[i_] == '-') ++i_;
    const bool leading_zero = i_ < s_.size() && s_[i_] == '0';
    const std::size_t whole = digits();
    if (whole == 0 || (leading_zero && whole > 1)) fail("a value expected");
    if (i_ < s_.size() && s_[i_] == '.') {
      ++i_;
      if (digits() == 0) fail("a digit expected after '.'");
    }
    if (i_ < s_.size() && (s_[i_] == 'e' || s_[i_] == 'E')) {
      ++i_;
      if (i_ < s_.size() && (s_[i_] == '+' || s_[i_] == '-')) ++i_;
      if (digits() == 0) fail("a digit expected in the exponent");
    }
    const double x = std::strtod(s_.substr(start, i_ - start).c_str(), nullptr);
    if (!std::isfinite(x)) fail("a number beyond double's range");
    return x;
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

double integer(const Json& v, const std::string& what) {
  if (v.type != Json::Type::Number || v.number != std::floor(v.number) || std::fabs(v.number) > 1e9)
    throw std::invalid_argument(what + " is not an integer");
  return v.number;
}

/** The numbers of an array of exactly `n`. */
void numbers(const Json& array, const std::string& name, std::size_t n, double* out) {
  const auto is_number = [](const Json& v) { return v.type == Json::Type::Number; };
  if (array.items.size() != n || !std::all_of(array.items.begin(), array.items.end(), is_number))
    throw std::invalid_argument("'" + name + "' takes " + std::to_string(n) + " numbers");
  for (std::size_t i = 0; i < n; ++i) out[i] = array.items[i].number;
}

TileIndex::Tile tile(const Json& v) {
  TileIndex::Tile t;
  t.name = "?";
  try {
    if (v.type != Json::Type::Object) throw std::invalid_argument("not an object");
    t.name = v.at("name", Json::Type::String).text;
    t.file = v.at("file", Json::Type::String).text;
    if (t.file.empty() || t.file[0] == '/' || t.file.find("..") != std::string::npos)
      throw std::invalid_argument("its file '" + t.file + "' lies outside the tile set");
    const double level = integer(v.at("level", Json::Type::Number), "its level");
    const Json& at = v.at("index", Json::Type::Array);
    if (level < 2 || level > 15 || at.items.size() != 3) throw std::invalid_argument("a bad level or index");
    t.level = int(level);
    for (int a = 0; a < 3; ++a) t.index[a] = std::int64_t(integer(at.items[std::size_t(a)], "its index"));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("tile " + t.name + ": " + e.what());
  }
  return t;
}

}  // namespace

TileIndex parseTileIndex(const std::string& text) {
  const Json index = JsonReader(text).document();
  if (index.type != Json::Type::Object || index.at("format", Json::Type::String).text != "pcl_fot tile set")
    throw std::invalid_argument("not a pcl_fot tile set index");
  TileIndex out;
  out.resolution = index.at("resolution", Json::Type::Number).number;
  numbers(index.at("origin", Json::Type::Array), "origin", 3, out.origin);
  numbers(index.at("sensor_model", Json::Type::Array), "sensor_model", 5, out.sensor_model);
  const std::string rule = index.at("rule", Json::Type::String).text;
  if (rule != "log_odds" && rule != "binary") throw std::invalid_argument("unknown rule '" + rule + "'");
  out.log_odds = rule == "log_odds";
  for (const Json& t : index.at("tiles", Json::Type::Array).items) out.tiles.push_back(tile(t));
  return out;
}

}  // namespace fot_tools
