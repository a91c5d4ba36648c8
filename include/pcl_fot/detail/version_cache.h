#pragma once

#include <cstdint>
#include <memory>
#include <mutex>

namespace pcl {
namespace fot {
namespace detail {

/**
 * A value built on demand from an object that changes, kept until the object's version moves on, or brought
 * along with a change in place. Const queries of the object may ask for it from many threads at once. A copy
 * starts empty: the value belongs to the object it was built from.
 */
template <typename T>
class VersionCache {
 public:
  VersionCache() = default;
  VersionCache(const VersionCache&) {}
  VersionCache& operator=(const VersionCache&) {
    std::lock_guard<std::mutex> lock(mutex_);
    value_.reset();
    return *this;
  }

  /** The value for this version: the kept one, or build()'s (a std::shared_ptr<T>). */
  template <typename Build>
  std::shared_ptr<const T> get(std::uint64_t version, Build&& build) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!value_ || version_ != version) {
      value_ = build();
      version_ = version;
    }
    return value_;
  }

  /**
   * The object went from version `from` to `to`: update(T&) brings the kept value along, if it is from `from`
   * and nobody else holds it. Otherwise, or if update throws, the value is dropped and built anew when asked.
   */
  template <typename Update>
  void follow(std::uint64_t from, std::uint64_t to, Update&& update) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!value_ || version_ != from || value_.use_count() != 1) {
      value_.reset();
      return;
    }
    try {
      update(*value_);
      version_ = to;
    } catch (...) {
      value_.reset();
    }
  }

 private:
  std::mutex mutex_;
  std::shared_ptr<T> value_;
  std::uint64_t version_ = 0;
};

}  // namespace detail
}  // namespace fot
}  // namespace pcl
