#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <pcl_fot/search/point_boxes.h>
#include <pcl_fot/tree/key.h>

namespace pcl {
namespace fot {
namespace detail {

/**
 * The updatable half of a PointIndex: each cell's points in a bucket of their own, found by the cell's key
 * in an open-addressing table, and each point's place found by its index. Adding or removing a point moves
 * no other point but the last of its bucket, so updates cost O(1) whatever the index holds.
 *
 * A crowded bucket's points are split into boxes (see PointBox), so that a search reads a few of them. The
 * boxes cover the bucket's first points; points added later form a tail that searches scan whole, and a
 * boxed point removed leaves a hole (NaN coordinates, which no search bound takes). settle(), at the end of
 * each batch of updates, splits a crowded bucket again once its tail and holes reach half its points: O(log
 * n) a change in the long run. No query may run between an update and settle().
 *
 * Memory follows the points held, not those ever added: a bucket that empties gives back its storage (but
 * for a few points' worth, kept for the next cell), one that thins out to a quarter shrinks, and the table
 * of cells halves when an eighth of it is used. The table by index is as long as the largest index held
 * (+1): a caller that reuses the indices of removed points (as FastOctTreeSearch does) keeps it as short as
 * the most points it held at once.
 */
class CellBuckets {
 public:
  void clear();
  /** Adds a point to the bucket of `cell`; returns true if the bucket was empty. The index must be new. */
  bool add(const Key& cell, const float p[3], std::int32_t index);
  /**
   * Removes the point `index`: false if it is not held. Else `cell` is its cell, and `emptied` tells whether
   * the cell now holds none.
   */
  bool remove(std::int32_t index, Key& cell, bool& emptied);
  /** Splits again the crowded buckets changed since the last call whose boxes cover too few of their points.
   */
  void settle();

  bool contains(std::int32_t index) const {
    return index >= 0 && std::size_t(index) < where_.size() && where_[std::size_t(index)] != kNowhere;
  }
  /** The point `index`, which must be held. */
  const BucketPoint& point(std::int32_t index) const {
    const std::uint64_t w = where_[std::size_t(index)];
    return buckets_[std::size_t(w >> 32)][std::uint32_t(w)];
  }
  /**
   * The points of `cell`, holes included (index -1): none if it holds none. A crowded cell's boxes, in
   * pre-order, go to `boxes` (positions in the points returned; those past the last box are not in any),
   * else nullptr.
   */
  const BucketPoint* find(const Key& cell, std::uint32_t& count, const PointBox*& boxes) const;
  std::size_t size() const { return size_; }
  /** Calls visit(point) for every point held. */
  template <typename Visit>
  void forEachPoint(Visit&& visit) const {
    for (const Slot& s : slots_)
      if (s.bucket != kFree)
        for (const BucketPoint& p : buckets_[s.bucket])
          if (p.index >= 0) visit(p);
  }
  std::size_t memoryBytes() const;

 private:
  static constexpr std::uint32_t kFree = ~std::uint32_t(0);
  static constexpr std::uint64_t kNowhere = ~std::uint64_t(0);
  /** A table slot: a cell and its bucket, kFree if the slot is unused. */
  struct Slot {
    Key cell;
    std::uint32_t bucket = kFree;
  };
  /** A bucket's cell and counts. */
  struct Info {
    Key cell;
    std::uint32_t live = 0;   // points held
    std::uint32_t holes = 0;  // removed points' places among the boxed ones
    std::uint32_t boxed = 0;  // the points the boxes cover: the first ones
    bool changed = false;     // since the last settle()
  };

  /** A bucket keeps up to this many points' storage when it empties or shrinks. */
  static constexpr std::size_t kKeptCapacity = 16;

  std::size_t home(const Key& cell) const;
  /** The slot of `cell`, or the free slot where it would go. */
  std::size_t probe(const Key& cell) const;
  /** The cells held: one per bucket in use. */
  std::size_t cells() const { return buckets_.size() - spare_.size(); }
  /** Moves the cells into a table of `size` slots, a power of two. */
  void rehash(std::size_t size);
  /** Frees slot i and shifts back the entries after it that probed past it. */
  void erase(std::size_t i);
  /** Notes that bucket b changed, for settle(). */
  void markChanged(std::uint32_t b);
  /** Bucket b without holes, boxed anew if crowded, its storage trimmed to its points. */
  void rebox(std::uint32_t b);

  std::vector<Slot> slots_;  // a power of two, at most half full
  std::vector<std::vector<BucketPoint>> buckets_;
  std::vector<std::vector<PointBox>> boxes_;  // by bucket: a crowded one's boxes
  std::vector<Info> info_;                    // by bucket
  std::vector<std::uint32_t> spare_;          // buckets no cell uses, kept for the next new cell
  std::vector<std::uint32_t> changed_;        // buckets changed since the last settle(), each once
  std::vector<std::uint64_t> where_;          // by point index: bucket << 32 | position in it
  std::size_t size_ = 0;
};

}  // namespace detail
}  // namespace fot
}  // namespace pcl
