#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <type_traits>
#include <vector>

#include <pcl/octree/octree_nodes.h>
#include <pcl/types.h>

#include <pcl_fot/pcl/octree/octree_containers.h>

namespace pcl {
namespace fot {

/**
 * A look-alike's leaves by slot (OctreeLeafTable's numbers), as PCL's leaf nodes. Leaves of point indices
 * (PCL's OctreeContainerPointIndices) made by a cloud's bulk insertion keep their indices as runs of one
 * array: no allocation a leaf. Such a leaf's container gets its run when a caller asks for the container,
 * and holds the leaf's indices from then on, as PCL's does. Other containers are always the leaf's own.
 *
 * Const callers may ask for containers from several threads; a change (add, drop, clear) needs the caller
 * alone, as PCL's octree does.
 */
template <typename LeafContainerT>
class OctreeLeafNodes {
 public:
  using LeafNode = octree::OctreeLeafNode<LeafContainerT>;
  using Slot = std::uint32_t;
  /** Whether bulk insertion keeps the leaves' indices in runs. */
  static constexpr bool kRuns = std::is_same<LeafContainerT, OctreeContainerPointIndices>::value;

  OctreeLeafNodes() = default;
  OctreeLeafNodes(const OctreeLeafNodes& other) { *this = other; }
  OctreeLeafNodes& operator=(const OctreeLeafNodes& other) {
    if (this == &other) return *this;
    const std::lock_guard<std::mutex> lock(other.moving_);  // no run moves into its container meanwhile
    entries_.clear();
    for (const Entry& e : other.entries_) {
      Entry& copy = entries_.emplace_back();
      copy.node = e.node;
      copy.begin = e.begin;
      copy.size = e.size;
      copy.in_node.store(e.in_node.load(std::memory_order_relaxed), std::memory_order_relaxed);
    }
    runs_ = other.runs_;
    live_ = other.live_;
    return *this;
  }

  /** The leaf at slot, its container holding its points. */
  LeafNode& node(Slot slot) const {
    Entry& e = entries_[slot];
    if constexpr (kRuns) {
      if (!e.in_node.load(std::memory_order_acquire)) {
        const std::lock_guard<std::mutex> lock(moving_);
        if (!e.in_node.load(std::memory_order_relaxed)) {
          e.node.getContainer().getPointIndicesVector().assign(run(e), run(e) + std::ptrdiff_t(e.size));
          live_ -= e.size;
          e.in_node.store(true, std::memory_order_release);
        }
      }
    }
    return e.node;
  }
  /** The leaf at slot; `created`: a new leaf, with an empty container. */
  LeafNode& reset(Slot slot, bool created) {
    if (slot == entries_.size()) return entries_.emplace_back().node;
    if (created) drop(slot);
    return node(slot);
  }
  /**
   * Makes room for `n` more indices in runs, first packing the runs if most of the array is indices of
   * leaves that hold their own or are gone.
   */
  void reserveRuns(std::size_t n) {
    if (runs_.size() > 2 * live_ + kSlack) pack();
    runs_.reserve(runs_.size() + n);
  }
  /** The new leaf at slot, holding indices[*first], .. indices[*(last - 1)] as a run. */
  void addRun(Slot slot, const std::uint32_t* first, const std::uint32_t* last, const index_t* indices) {
    static_assert(kRuns, "only leaves of point indices keep runs");
    reset(slot, true);
    Entry& e = entries_[slot];
    e.begin = std::uint32_t(runs_.size());
    e.size = std::uint32_t(last - first);
    for (; first != last; ++first) runs_.push_back(indices[*first]);
    live_ += e.size;
    e.in_node.store(false, std::memory_order_relaxed);
  }
  /** Appends the indices of the leaf at slot. */
  void appendIndices(Slot slot, Indices& out) const {
    const Entry& e = entries_[slot];
    if (kRuns && !e.in_node.load(std::memory_order_acquire))
      out.insert(out.end(), run(e), run(e) + std::ptrdiff_t(e.size));
    else
      e.node.getContainer().getPointIndices(out);
  }
  /** The number of points of the leaf at slot, as its container counts them. */
  std::size_t size(Slot slot) const {
    const Entry& e = entries_[slot];
    if (kRuns && !e.in_node.load(std::memory_order_acquire)) return e.size;
    return e.node.getContainer().getSize();
  }
  /** The leaf at slot is gone: its node is emptied and its run, if it has one, no longer read. */
  void drop(Slot slot) {
    Entry& e = entries_[slot];
    if (!e.in_node.load(std::memory_order_relaxed)) live_ -= e.size;
    e.in_node.store(true, std::memory_order_relaxed);
    e.node = LeafNode();
  }
  /** Indices in runs, those no longer read included: reserveRuns packs them. */
  std::size_t runIndices() const { return runs_.size(); }
  void clear() {
    entries_.clear();
    runs_.clear();
    runs_.shrink_to_fit();
    live_ = 0;
  }

 private:
  // Indices of gone leaves a bulk insertion may leave behind before the runs are packed.
  static constexpr std::size_t kSlack = 4096;

  struct Entry {
    LeafNode node;
    std::uint32_t begin = 0, size = 0;  // the run, while the node does not hold the indices
    std::atomic<bool> in_node{true};    // set once the container holds them: then it is the leaf's
  };

  std::vector<index_t>::const_iterator run(const Entry& e) const {
    return runs_.begin() + std::ptrdiff_t(e.begin);
  }
  /** Moves the live runs to the front of a new array, in slot order. */
  void pack() {
    std::vector<index_t> packed;
    packed.reserve(live_);
    for (Entry& e : entries_) {
      if (e.in_node.load(std::memory_order_relaxed)) continue;
      const auto from = run(e);
      e.begin = std::uint32_t(packed.size());
      packed.insert(packed.end(), from, from + std::ptrdiff_t(e.size));
    }
    runs_.swap(packed);
  }

  mutable std::deque<Entry> entries_;  // a deque keeps leaves in place as it grows
  std::vector<index_t> runs_;
  mutable std::size_t live_ = 0;  // indices of runs still read
  mutable std::mutex moving_;     // a run moving into its container
};

}  // namespace fot
}  // namespace pcl
