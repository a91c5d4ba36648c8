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
 * array: no node and no allocation a leaf. Such a leaf gets a node when a caller asks for its container,
 * with the run copied in, and the container holds the leaf's indices from then on, as PCL's does. Leaves of
 * other containers are nodes from the start.
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
    const std::lock_guard<std::mutex> lock(other.moving_);  // no run moves into a node meanwhile
    clear();
    for (const Entry& e : other.entries_) {
      Entry& copy = entries_.emplace_back();
      if constexpr (kRuns) {
        copy.begin = e.begin;
        copy.size = e.size;
        if (const LeafNode* n = e.node.load(std::memory_order_relaxed))
          copy.node.store(&nodes_.emplace_back(*n), std::memory_order_relaxed);
      } else {
        copy = e;
      }
    }
    runs_ = other.runs_;
    live_ = other.live_;
    return *this;
  }

  /** The leaf at slot, its container holding its points. */
  LeafNode& node(Slot slot) const {
    if constexpr (kRuns) {
      Entry& e = entries_[slot];
      if (LeafNode* n = e.node.load(std::memory_order_acquire)) return *n;
      const std::lock_guard<std::mutex> lock(moving_);
      LeafNode* n = e.node.load(std::memory_order_relaxed);
      if (!n) {
        n = spareNode();
        n->getContainer().getPointIndicesVector().assign(run(e), run(e) + std::ptrdiff_t(e.size));
        live_ -= e.size;
        e.node.store(n, std::memory_order_release);
      }
      return *n;
    } else {
      return entries_[slot];
    }
  }
  /** The leaf at slot; `created`: a new leaf, with an empty container. */
  LeafNode& reset(Slot slot, bool created) {
    if (slot == entries_.size())
      entries_.emplace_back();
    else if (created)
      drop(slot);
    return node(slot);
  }
  /**
   * Makes room for `n` more indices in runs, first packing the runs if most of the array is indices of
   * leaves that have nodes or are gone.
   */
  void reserveRuns(std::size_t n) {
    if (runs_.size() > 2 * live_ + kSlack) pack();
    runs_.reserve(runs_.size() + n);
  }
  /** The new leaf at slot, holding indices[*first], .. indices[*(last - 1)] as a run. */
  void addRun(Slot slot, const std::uint32_t* first, const std::uint32_t* last, const index_t* indices) {
    static_assert(kRuns, "only leaves of point indices keep runs");
    if (slot == entries_.size())
      entries_.emplace_back();
    else
      drop(slot);
    Entry& e = entries_[slot];
    e.begin = std::uint32_t(runs_.size());
    e.size = std::uint32_t(last - first);
    for (; first != last; ++first) runs_.push_back(indices[*first]);
    live_ += e.size;
  }
  /** Appends the indices of the leaf at slot. */
  void appendIndices(Slot slot, Indices& out) const {
    if constexpr (kRuns) {
      const Entry& e = entries_[slot];
      if (const LeafNode* n = e.node.load(std::memory_order_acquire))
        n->getContainer().getPointIndices(out);
      else
        out.insert(out.end(), run(e), run(e) + std::ptrdiff_t(e.size));
    } else {
      entries_[slot].getContainer().getPointIndices(out);
    }
  }
  /** The number of points of the leaf at slot, as its container counts them. */
  std::size_t size(Slot slot) const {
    if constexpr (kRuns) {
      const Entry& e = entries_[slot];
      const LeafNode* n = e.node.load(std::memory_order_acquire);
      return n ? n->getContainer().getSize() : e.size;
    } else {
      return entries_[slot].getContainer().getSize();
    }
  }
  /** The leaf at slot is gone: its container is emptied, its run no longer read. */
  void drop(Slot slot) {
    if constexpr (kRuns) {
      Entry& e = entries_[slot];
      if (LeafNode* n = e.node.load(std::memory_order_relaxed)) {
        *n = LeafNode();
        spare_.push_back(n);
        e.node.store(nullptr, std::memory_order_relaxed);
      } else {
        live_ -= e.size;
      }
      e.size = 0;
    } else {
      entries_[slot] = LeafNode();
    }
  }
  /** Indices in runs, those no longer read included: reserveRuns packs them. */
  std::size_t runIndices() const { return runs_.size(); }
  void clear() {
    entries_.clear();
    nodes_.clear();
    spare_.clear();
    runs_.clear();
    runs_.shrink_to_fit();
    live_ = 0;
  }

 private:
  // Indices of gone leaves a bulk insertion may leave behind before the runs are packed.
  static constexpr std::size_t kSlack = 4096;

  struct RunEntry {
    std::atomic<LeafNode*> node{nullptr};  // set once the leaf has a node: its container holds the indices
    std::uint32_t begin = 0, size = 0;     // the run, while it has none
  };
  using Entry = std::conditional_t<kRuns, RunEntry, LeafNode>;

  std::vector<index_t>::const_iterator run(const RunEntry& e) const {
    return runs_.begin() + std::ptrdiff_t(e.begin);
  }
  /** A node with an empty container, for a leaf of runs (under moving_ when const). */
  LeafNode* spareNode() const {
    if (spare_.empty()) return &nodes_.emplace_back();
    LeafNode* n = spare_.back();
    spare_.pop_back();
    return n;
  }
  /** Moves the live runs to the front of a new array, in slot order. */
  void pack() {
    std::vector<index_t> packed;
    packed.reserve(live_);
    for (RunEntry& e : entries_) {
      if (e.node.load(std::memory_order_relaxed)) continue;
      const auto from = run(e);
      e.begin = std::uint32_t(packed.size());
      packed.insert(packed.end(), from, from + std::ptrdiff_t(e.size));
    }
    runs_.swap(packed);
  }

  // Deques keep leaves and nodes in place as they grow. Mutable as PCL's nodes are: const look-ups hand out
  // leaves callers may fill.
  mutable std::deque<Entry> entries_;
  mutable std::deque<LeafNode> nodes_;    // the nodes of leaves of runs, made when asked for
  mutable std::vector<LeafNode*> spare_;  // nodes of gone leaves, for the next ones
  std::vector<index_t> runs_;
  mutable std::size_t live_ = 0;  // indices of runs still read
  mutable std::mutex moving_;     // a node being made for a leaf of runs
};

}  // namespace fot
}  // namespace pcl
