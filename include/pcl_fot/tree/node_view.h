#pragma once

#include <cstddef>

#include <pcl_fot/tree/node_word.h>
#include <pcl_fot/tree/tree_coord.h>

namespace pcl {
namespace fot {

/**
 * A node as a walk through the tree sees it: its word, its level (it spans 2^level cells per axis) and the
 * lowest corner of its cube, in tree coordinates. Nodes store no coordinates; a walk carries them down
 * with child(). An octant of a bitmap word reads as a uniform word one level down, so a walk descends
 * through bitmaps and references alike. A view is a few registers: copy it freely.
 */
struct NodeView {
  NodeWord word;
  unsigned level;
  TreeCoord corner;

  bool isBitmap() const { return node::isBitmap(word); }
  bool isUniform() const { return node::isUniform(word); }
  CellState uniformState() const { return node::uniformState(word); }
  /** Cells per axis of a child's cube. */
  std::uint32_t childSide() const { return std::uint32_t(1) << (level - 1); }

  /** Child o's word: from the pool for a reference, the octant as a uniform word for a bitmap. */
  static NodeWord childWord(const NodeWord* words, NodeWord w, unsigned o) {
    return node::isBitmap(w) ? node::uniform(node::state(w, o)) : words[node::childOffset(w, o)];
  }
  NodeView child(const NodeWord* words, unsigned o) const {
    return NodeView{childWord(words, word, o), level - 1, corner.child(o, level - 1)};
  }
  /** Child o's pool offset; the view must be a reference. */
  std::size_t childOffset(unsigned o) const { return node::childOffset(word, o); }
};

}  // namespace fot
}  // namespace pcl
