#include <pcl_fot/search/cell_buckets.h>

#include <algorithm>
#include <limits>

namespace pcl {
namespace fot {
namespace detail {

void CellBuckets::clear() {
  slots_.clear();
  buckets_.clear();
  boxes_.clear();
  info_.clear();
  spare_.clear();
  changed_.clear();
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
      boxes_.emplace_back();
      info_.emplace_back();
    }
    info_[b].cell = cell;
    slots_[i] = Slot{cell, b};
  }
  const std::uint32_t b = slots_[i].bucket;
  std::vector<BucketPoint>& bucket = buckets_[b];
  if (std::size_t(index) >= where_.size()) where_.resize(std::size_t(index) + 1, kNowhere);
  where_[std::size_t(index)] = std::uint64_t(b) << 32 | std::uint32_t(bucket.size());
  bucket.push_back(BucketPoint{{p[0], p[1], p[2]}, index});
  ++info_[b].live;
  ++size_;
  markChanged(b);
  return fresh;
}

bool CellBuckets::remove(std::int32_t index, Key& cell, bool& emptied) {
  if (!contains(index)) return false;
  const std::uint64_t w = where_[std::size_t(index)];
  const std::uint32_t b = std::uint32_t(w >> 32), at = std::uint32_t(w);
  std::vector<BucketPoint>& bucket = buckets_[b];
  Info& info = info_[b];
  if (at >= info.boxed) {  // in the tail: the last point takes its place
    bucket[at] = bucket.back();
    where_[std::size_t(bucket[at].index)] = std::uint64_t(b) << 32 | at;
    bucket.pop_back();
  } else {  // in a box: a hole, which keeps the boxes right
    const float nan = std::numeric_limits<float>::quiet_NaN();
    bucket[at] = BucketPoint{{nan, nan, nan}, -1};
    ++info.holes;
  }
  where_[std::size_t(index)] = kNowhere;
  --size_;
  --info.live;
  cell = info.cell;
  emptied = info.live == 0;
  markChanged(b);
  if (emptied) {
    erase(probe(cell));
    spare_.push_back(b);
    // A spare bucket keeps a few points' storage for the next cell, no more; the table halves once an
    // eighth of it is used (it doubles at a half), so memory follows the cells held.
    bucket.clear();
    if (bucket.capacity() > kKeptCapacity) std::vector<BucketPoint>().swap(bucket);
    std::vector<PointBox>().swap(boxes_[b]);
    info.holes = info.boxed = 0;
    if (slots_.size() > 16 && 8 * cells() < slots_.size()) rehash(slots_.size() / 2);
  }
  return true;
}

void CellBuckets::markChanged(std::uint32_t b) {
  if (info_[b].changed) return;
  info_[b].changed = true;
  changed_.push_back(b);
}

void CellBuckets::settle() {
  for (const std::uint32_t b : changed_) {
    Info& info = info_[b];
    info.changed = false;
    const std::size_t n = buckets_[b].size();
    // Split again once the tail and the holes reach half the points: each split of m points follows at
    // least m / 2 changes. A bucket no longer crowded loses its boxes and holes.
    const std::size_t stale = (n - info.boxed) + info.holes;
    const bool crowded = info.live > kCrowded;
    if (crowded ? (info.boxed == 0 || 2 * stale >= info.live) : info.boxed > 0) rebox(b);
  }
  changed_.clear();
}

void CellBuckets::rebox(std::uint32_t b) {
  std::vector<BucketPoint>& bucket = buckets_[b];
  std::vector<PointBox>& boxes = boxes_[b];
  Info& info = info_[b];
  bucket.erase(std::remove_if(bucket.begin(), bucket.end(), [](const BucketPoint& p) { return p.index < 0; }),
               bucket.end());
  boxes.clear();
  if (bucket.size() > kCrowded)
    splitIntoBoxes(bucket.data(), std::uint32_t(bucket.size()), 0, boxes);
  else
    std::vector<PointBox>().swap(boxes);
  info.holes = 0;
  info.boxed = std::uint32_t(boxes.empty() ? 0 : bucket.size());
  // A bucket thinned out to a quarter gives back half its storage, O(1) a point in the long run.
  if (bucket.capacity() > kKeptCapacity && 4 * bucket.size() < bucket.capacity()) {
    std::vector<BucketPoint> smaller;
    smaller.reserve(std::max(kKeptCapacity, 2 * bucket.size()));
    smaller.assign(bucket.begin(), bucket.end());
    bucket.swap(smaller);
  }
  for (std::uint32_t at = 0; at < bucket.size(); ++at)
    where_[std::size_t(bucket[at].index)] = std::uint64_t(b) << 32 | at;
}

const BucketPoint* CellBuckets::find(const Key& cell, std::uint32_t& count, const PointBox*& boxes) const {
  count = 0;
  boxes = nullptr;
  if (slots_.empty()) return nullptr;
  const Slot& s = slots_[probe(cell)];
  if (s.bucket == kFree) return nullptr;
  const std::vector<BucketPoint>& bucket = buckets_[s.bucket];
  count = std::uint32_t(bucket.size());
  if (!boxes_[s.bucket].empty()) boxes = boxes_[s.bucket].data();
  return bucket.data();
}

std::size_t CellBuckets::memoryBytes() const {
  std::size_t bytes = slots_.capacity() * sizeof(Slot) + buckets_.capacity() * sizeof(buckets_[0]) +
                      boxes_.capacity() * sizeof(boxes_[0]) + info_.capacity() * sizeof(Info) +
                      (spare_.capacity() + changed_.capacity()) * sizeof(std::uint32_t) +
                      where_.capacity() * sizeof(std::uint64_t);
  for (const auto& b : buckets_) bytes += b.capacity() * sizeof(BucketPoint);
  for (const auto& b : boxes_) bytes += b.capacity() * sizeof(PointBox);
  return bytes;
}

}  // namespace detail
}  // namespace fot
}  // namespace pcl
