#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace pcl {
namespace fot {
namespace detail {

/**
 * Rows of N values of T in fixed pages of 512 rows: they grow without copying and without a doubled
 * vector's slack, and freed rows are handed out again. The tree keeps its leaves' values in them.
 */
template <typename T, std::size_t N>
class RowPages {
 public:
  static constexpr unsigned kPageBits = 9;
  static constexpr std::size_t kPageBytes = (N << kPageBits) * sizeof(T);

  T* at(std::uint32_t r) { return &pages_[r >> kPageBits][N * std::size_t(r & kPageMask)]; }
  const T* at(std::uint32_t r) const { return &pages_[r >> kPageBits][N * std::size_t(r & kPageMask)]; }

  /** Bytes the next allocate() adds: a page, or nothing when a freed row is at hand. */
  std::size_t growth() const { return free_.empty() ? kPageBytes : 0; }
  std::uint32_t allocate() {
    ++live_;
    if (!free_.empty()) {
      const std::uint32_t r = free_.back();
      free_.pop_back();
      return r;
    }
    if ((made_ >> kPageBits) == pages_.size()) pages_.emplace_back(N << kPageBits);
    return made_++;
  }
  /** Frees a row; the last one frees the pages. */
  void release(std::uint32_t r) {
    free_.push_back(r);
    if (--live_ == 0) clear();
  }
  void clear() {
    std::vector<std::vector<T>>().swap(pages_);
    std::vector<std::uint32_t>().swap(free_);
    made_ = 0;
    live_ = 0;
  }
  void shrinkToFit() { free_.shrink_to_fit(); }

  std::size_t live() const { return live_; }
  std::size_t bytes() const {
    return pages_.size() * kPageBytes + pages_.capacity() * sizeof(pages_[0]) +
           free_.capacity() * sizeof(std::uint32_t);
  }

 private:
  static constexpr std::uint32_t kPageMask = (1u << kPageBits) - 1;
  std::vector<std::vector<T>> pages_;
  std::vector<std::uint32_t> free_;
  std::uint32_t made_ = 0;  // rows handed out of the pages, free ones included
  std::size_t live_ = 0;
};

}  // namespace detail
}  // namespace fot
}  // namespace pcl
