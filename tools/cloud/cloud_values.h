#pragma once
// What the PCD and PLY parsers share: a cursor over the file's bytes, header lines, and numbers stored in
// binary or as text.

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <system_error>
#include <vector>

#include "cloud_parser.h"

namespace fot_tools {
namespace cloud_values {

[[noreturn]] inline void damaged(const std::string& why) {
  throw CloudFileError("is damaged or truncated: " + why);
}

/** a·b, or the largest value where that overflows: sizes a header claims are compared, never allocated. */
inline std::uint64_t times(std::uint64_t a, std::uint64_t b) {
  return b != 0 && a > std::numeric_limits<std::uint64_t>::max() / b
             ? std::numeric_limits<std::uint64_t>::max()
             : a * b;
}

/** A number type: kind 'I' (signed), 'U' (unsigned) or 'F' (floating point), of `size` bytes. */
struct ValueType {
  char kind = 'F';
  unsigned size = 4;
};

inline bool isValid(ValueType t) {
  if (t.kind == 'F') return t.size == 4 || t.size == 8;
  return (t.kind == 'I' || t.kind == 'U') && (t.size == 1 || t.size == 2 || t.size == 4 || t.size == 8);
}

/** The value of type t stored at p, in little-endian byte order unless big_endian. */
inline double binaryValue(const unsigned char* p, ValueType t, bool big_endian) {
  std::uint64_t bits = 0;
  for (unsigned i = 0; i < t.size; ++i) bits |= std::uint64_t(p[big_endian ? t.size - 1 - i : i]) << (8 * i);
  if (t.kind == 'F') {
    if (t.size == 8) {
      double d;
      std::memcpy(&d, &bits, sizeof d);
      return d;
    }
    const std::uint32_t low = std::uint32_t(bits);
    float f;
    std::memcpy(&f, &low, sizeof f);
    return f;
  }
  if (t.kind == 'I') {
    const unsigned unused = 64 - 8 * t.size;  // sign-extend from the type's top bit
    return double(std::int64_t(bits << unused) >> unused);
  }
  return double(bits);
}

/** A double as a float; beyond float's range, an infinity of its sign. */
inline float toFloat(double v) {
  if (std::isnan(v) || std::abs(v) <= double(std::numeric_limits<float>::max())) return float(v);
  return std::copysign(std::numeric_limits<float>::infinity(), float(v));
}

/** A number written as text: decimal, or nan / inf as printf writes them. False if the word is none. */
inline bool textValue(const char* first, const char* last, double& v) {
  if (first != last && *first == '+') ++first;
  const std::from_chars_result r = std::from_chars(first, last, v);
  if (r.ptr != last || first == last) return false;
  if (r.ec ==
      std::errc::result_out_of_range) {  // from_chars leaves v alone: overflow to ±inf, underflow to ±0
    const bool negative = *first == '-';
    const char* e = first;
    while (e != last && *e != 'e' && *e != 'E') ++e;
    const bool underflow = e != last && e + 1 != last && e[1] == '-';
    v = std::copysign(underflow ? 0.0 : std::numeric_limits<double>::infinity(), negative ? -1.0 : 1.0);
    return true;
  }
  return r.ec == std::errc();
}

/** A count in a header: decimal digits only. */
inline bool countValue(const std::string& word, std::uint64_t& v) {
  if (word.empty() || word.size() > 19) return false;
  v = 0;
  for (char c : word) {
    if (c < '0' || c > '9') return false;
    v = v * 10 + std::uint64_t(c - '0');
  }
  return true;
}

/** The bytes of a file, read front to back. */
class Cursor {
 public:
  Cursor(const char* data, std::size_t size) : at_(data), end_(data + size) {}

  std::size_t left() const { return std::size_t(end_ - at_); }

  /**
   * The next line split into words. False at the end of the bytes, and for a line longer than any header
   * line: the bytes of a file that is no cloud need not hold a line end at all.
   */
  bool headerLine(std::vector<std::string>& words) {
    if (at_ == end_) return false;
    const std::size_t most = std::min<std::size_t>(left(), kMaxHeaderLine);
    const char* line_end = static_cast<const char*>(std::memchr(at_, '\n', most));
    if (!line_end && most < left()) return false;
    const char* stop = line_end ? line_end : end_;
    words.clear();
    for (const char* p = at_; p != stop;) {
      while (p != stop && isSpace(*p)) ++p;
      const char* w = p;
      while (p != stop && !isSpace(*p)) ++p;
      if (p != w) words.emplace_back(w, p);
    }
    at_ = line_end ? line_end + 1 : end_;
    return true;
  }

  /** The next n bytes, or nullptr if fewer are left. */
  const unsigned char* take(std::uint64_t n) {
    if (n > left()) return nullptr;
    const unsigned char* p = reinterpret_cast<const unsigned char*>(at_);
    at_ += n;
    return p;
  }

  /** The next word of a text body, between white space; false at the end. */
  bool word(const char*& first, const char*& last) {
    while (at_ != end_ && isSpace(*at_)) ++at_;
    first = at_;
    while (at_ != end_ && !isSpace(*at_)) ++at_;
    last = at_;
    return first != last;
  }

 private:
  static constexpr std::size_t kMaxHeaderLine = 1 << 20;
  static bool isSpace(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
  }

  const char* at_;
  const char* end_;
};

}  // namespace cloud_values
}  // namespace fot_tools
