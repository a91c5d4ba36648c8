#include <pcl_fot/search/cell_buckets.h>

#include <algorithm>

namespace pcl {
namespace fot {
namespace detail {

void CellBuckets::clear() {
  slots_.clear();
  buckets_.clear();
  cell_of_.clear();
  spare_.clear();
  where_.clear();
  size_ = 0;
}

std::size_t CellBuckets::home(const Key& cell) const {
  // The top bits of the hash: neighbouring cells land far apart, so runs of used slots stay short.
  return std::size_t((std::uint64_t(KeyHash()(cell)) * 0x9E3779B97F4A7C15ull) >> 32) & (slots_.size() - 1);
}

std::size_t CellBuckets::probe(const Key& cell) const {
  std::size_t i = home(cell);
  while (slots_[i].bucket != kFree && slots_[i].cell != cell) i = (i + 1) & (slots_.size() - 1);
  return i;
}

void CellBuckets::rehash(std::size_t size) {
  std::vector<Slot> old(size);
  old.swap(slots_);
  for (const Slot& s : old)
    if (s.bucket != kFree) slots_[probe(s.cell)] = s;
}

void CellBuckets::erase(std::size_t i) {
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t j = (i + 1) & mask; slots_[j].bucket != kFree; j = (j + 1) & mask) {
    // An entry may move back to i unless its home lies cyclically in (i, j].
    const std::size_t h = home(slots_[j].cell);
    if (((j - h) & mask) >= ((j - i) & mask)) {
      slots_[i] = slots_[j];
      i = j;
    }
  }
  slots_[i].bucket = kFree;
}

bool CellBuckets::add(const Key& cell, const float p[3], std::int32_t index) {
  if (2 * (cells() + 1) > slots_.size()) rehash(slots_.empty() ? 16 : 2 * slots_.size());
  const std::size_t i = probe(cell);
  const bool fresh = slots_[i].bucket == kFree;
  if (fresh) {
    std::uint32_t b;
    if (!spare_.empty()) {
      b = spare_.back();
      spare_.pop_back();
    } else {
      b = std::uint32_t(buckets_.size());
      buckets_.emplace_back();
      cell_of_.emplace_back();
    }
    cell_of_[b] = cell;
    slots_[i] = Slot{cell, b};
  }
  std::vector<BucketPoint>& bucket = buckets_[slots_[i].bucket];
  if (std::size_t(index) >= where_.size()) where_.resize(std::size_t(index) + 1, kNowhere);
  where_[std::size_t(index)] = std::uint64_t(slots_[i].bucket) << 32 | std::uint32_t(bucket.size());
  bucket.push_back(BucketPoint{{p[0], p[1], p[2]}, index});
  ++size_;
  return fresh;
}

bool CellBuckets::remove(std::int32_t index, Key& cell, bool& emptied) {
  if (!contains(index)) return false;
  const std::uint64_t w = where_[std::size_t(index)];
  const std::uint32_t b = std::uint32_t(w >> 32), at = std::uint32_t(w);
  std::vector<BucketPoint>& bucket = buckets_[b];
  bucket[at] = bucket.back();
  where_[std::size_t(bucket[at].index)] = std::uint64_t(b) << 32 | at;
  bucket.pop_back();
  where_[std::size_t(index)] = kNowhere;
  --size_;
  cell = cell_of_[b];
  emptied = bucket.empty();
  if (emptied) {
    erase(probe(cell));
    spare_.push_back(b);
    // A spare bucket keeps a few points' storage for the next cell, no more; the table halves once an
    // eighth of it is used (it doubles at a half), so memory follows the cells held.
    if (bucket.capacity() > kKeptCapacity) std::vector<BucketPoint>().swap(bucket);
    if (slots_.size() > 16 && 8 * cells() < slots_.size()) rehash(slots_.size() / 2);
  } else if (bucket.capacity() > kKeptCapacity && 4 * bucket.size() < bucket.capacity()) {
    // A bucket thinned out to a quarter: half its storage goes, O(1) a point in the long run. The points
    // keep their positions, so where_ holds.
    std::vector<BucketPoint> smaller;
    smaller.reserve(std::max(kKeptCapacity, 2 * bucket.size()));
    smaller.assign(bucket.begin(), bucket.end());
    bucket.swap(smaller);
  }
  return true;
}

const BucketPoint* CellBuckets::find(const Key& cell, std::uint32_t& count) const {
  count = 0;
  if (slots_.empty()) return nullptr;
  const Slot& s = slots_[probe(cell)];
  if (s.bucket == kFree) return nullptr;
  const std::vector<BucketPoint>& bucket = buckets_[s.bucket];
  count = std::uint32_t(bucket.size());
  return bucket.data();
}

std::size_t CellBuckets::memoryBytes() const {
  std::size_t bytes = slots_.capacity() * sizeof(Slot) + buckets_.capacity() * sizeof(buckets_[0]) +
                      cell_of_.capacity() * sizeof(Key) + spare_.capacity() * sizeof(std::uint32_t) +
                      where_.capacity() * sizeof(std::uint64_t);
  for (const auto& b : buckets_) bytes += b.capacity() * sizeof(BucketPoint);
  return bytes;
}

}  // namespace detail
}  // namespace fot
}  // namespace pcl
