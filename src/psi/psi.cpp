#include <pcl_fot/psi/psi.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <vector>

#include <pcl_fot/detail/bits.h>
#include <pcl_fot/detail/worker_threads.h>
#include <pcl_fot/search/nearest_cell_search.h>
#include <pcl_fot/tree/accessor.h>

#include "psi/psi_sum.h"
#include "search/brick_distance.h"

namespace pcl {
namespace fot {
namespace {

std::uint64_t cellCount(const FastOctTree& t, CellState v) {
  return v == CellState::Occupied ? t.getOccupiedCount() : t.getFreeCount();
}

/**
 * A piece of a's cells in Morton order: a node at a brick's level or below (cells read bit by bit), or a
 * uniform cube above it.
 */
using Piece = NodeView;

/** a's pieces holding v, in Morton order. */
void collectPieces(const NodeWord* words, const NodeView& n, CellState v, std::vector<Piece>& out) {
  if (n.isUniform()) {
    if (n.uniformState() == v) out.push_back(n);
    return;
  }
  if (n.level <= detail::kBrickLevel) {
    if (!n.isBitmap() || node::holds(n.word, v)) out.push_back(n);
    return;
  }
  for (unsigned o = 0; o < 8; ++o) {
    const NodeWord child = NodeView::childWord(words, n.word, o);
    if (node::isBitmap(child) && !node::holds(child, v)) continue;  // most, in sparse maps
    collectPieces(words, NodeView{child, n.level - 1, n.corner.child(o, n.level - 1)}, v, out);
  }
}

/**
 * Sums a's cells' distances to b's cells of one value, for a run of a's pieces. Cells are taken a 16³ brick
 * at a time. Bit dilation of b's cells around the brick settles those within 8 cells, then those within
 * 16; the nearest-tree-neighbour search finds the rest, and the cells of bricks too sparse to be worth a
 * window, each query starting from the previous one's path.
 */
class DirectedSum {
 public:
  DirectedSum(const FastOctTree& a, const FastOctTree& b, CellState v, std::int64_t cap)
      : a_words_(a.words()),
        v_(v),
        cap_(cap),
        windows_(b, v),
        search_(b, Metric::Manhattan, v),
        b_cells_(b) {}

  std::uint64_t pieces(const Piece* first, const Piece* last) {
    std::uint64_t sum = 0;
    for (const Piece* p = first; p != last; ++p) {
      if (p->level >= detail::kBrickLevel && p->isUniform()) {
        sum += cube(p->corner, p->level);
        continue;
      }
      const TreeCoord corner = p->corner.corner(detail::kBrickLevel);  // below a brick only in a tiny tree
      detail::Brick cells;
      cells.setFromWord(a_words_, p->word, p->level, p->corner[0] - corner[0], p->corner[1] - corner[1],
                        p->corner[2] - corner[2], v_);
      if (cells.any()) sum += brick(corner.u, cells);
    }
    return sum;
  }

 private:
  /** A cube of a's cells, all holding v, of at least a brick: zero if b holds v throughout, else by bricks.
   */
  std::uint64_t cube(const TreeCoord& corner, unsigned level) {
    // The maps share their grid, so the cube is aligned in b too: b holds one state throughout it when the
    // bitmap octant holding its corner is at least as large.
    const unsigned bottom = b_cells_.locatePath(corner.key());
    if (bottom > level &&
        node::state(b_cells_.tree().words()[b_cells_.pathOffset(bottom)], corner.octant(bottom)) == v_)
      return 0;
    if (level == detail::kBrickLevel) {
      detail::Brick full;
      full.bits.fill(~std::uint64_t(0));
      return brick(corner.u, full);
    }
    std::uint64_t sum = 0;
    for (unsigned o = 0; o < 8; ++o) sum += cube(corner.child(o, level - 1), level - 1);
    return sum;
  }

  std::uint64_t brick(const std::uint32_t corner[3], detail::Brick& cells) {
    std::uint64_t sum = 0;
    const std::int64_t settled =
        windows_.settle(corner, cells, cap_, [&sum](unsigned d, unsigned, std::uint64_t bits) {
          sum += std::uint64_t(d) * detail::popcount64(bits);
        });
    if (cap_ <= settled) {  // every cell left is at least cap away
      sum += std::uint64_t(cap_) * cells.count();
      return sum;
    }
    // The rest take the walk, but one walk settles many: see Certificate. The first cell left picks the
    // sweep, towards its nearest cell along each axis, so that later cells lie between earlier ones and
    // their nearest cells. A brick too sparse for a window is too sparse for the order to matter.
    floor_ = settled + 1;
    constexpr unsigned side = detail::Brick::kSide;
    certificate_count_ = 0;
    if (settled < 0) {
      for (unsigned w = 0; w < detail::Brick::kWords; ++w)
        for (std::uint64_t bits = cells.bits[w]; bits; bits &= bits - 1) {
          const unsigned i = w * 64 + detail::lowestBit(bits);
          sum += distance(cellKey(corner, i % side, (i / side) % side, i / (side * side)));
        }
      return sum;
    }
    if (!cells.any()) return sum;
    unsigned w = 0;
    while (cells.bits[w] == 0) ++w;
    const unsigned i = w * 64 + detail::lowestBit(cells.bits[w]);
    cells.bits[w] &= cells.bits[w] - 1;
    const Key q0 = cellKey(corner, i % side, (i / side) % side, i / (side * side));
    sum += distance(q0);
    int dir[3] = {1, 1, 1};
    if (certificate_count_ > 0) {
      const Key& m = certificates_[0].match;
      dir[0] = m.x >= q0.x ? 1 : -1, dir[1] = m.y >= q0.y ? 1 : -1, dir[2] = m.z >= q0.z ? 1 : -1;
    }
    constexpr unsigned slab_words = side * side / 64;
    for (unsigned zi = 0; zi < side; ++zi) {
      const unsigned z = dir[2] > 0 ? zi : side - 1 - zi;
      std::uint64_t slab = 0;  // sparse bricks skip their empty slabs whole
      for (unsigned k = 0; k < slab_words; ++k) slab |= cells.bits[z * slab_words + k];
      if (slab == 0) continue;
      for (unsigned yi = 0; yi < side; ++yi) {
        const unsigned y = dir[1] > 0 ? yi : side - 1 - yi;
        const std::uint64_t row = cells.row(y, z);
        if (row == 0) continue;
        for (unsigned xi = 0; xi < side; ++xi) {
          const unsigned x = dir[0] > 0 ? xi : side - 1 - xi;
          if ((row >> x) & 1u) sum += distance(cellKey(corner, x, y, z));
        }
      }
    }
    return sum;
  }

  static Key cellKey(const std::uint32_t corner[3], unsigned x, unsigned y, unsigned z) {
    return TreeCoord(corner[0] + x, corner[1] + y, corner[2] + z).key();
  }

  /**
   * A walk's answer for cell c, nearest cell m at distance d, bounds the distance of every cell q:
   * d - |c - q| <= d(q) <= |q - m|. The bounds meet in the box spanned by c and m, and where those of
   * different walks meet; otherwise the lower one still lets q's walk stop at the first cell that near.
   */
  struct Certificate {
    Key query, match;
    std::int64_t distance;
  };
  static constexpr unsigned kCertificates = 8;  // the latest walks' answers, newest last

  static std::int64_t manhattan(const Key& a, const Key& b) {
    return std::llabs(std::int64_t(a.x) - b.x) + std::llabs(std::int64_t(a.y) - b.y) +
           std::llabs(std::int64_t(a.z) - b.z);
  }

  std::uint64_t distance(const Key& q) {
    std::int64_t lower = floor_, upper = NearestCellSearch::kUnbounded;
    const unsigned n = std::min(certificate_count_, kCertificates);
    for (unsigned k = 0; k < n; ++k) {
      const Certificate& c = certificates_[k];
      lower = std::max(lower, c.distance - manhattan(q, c.query));
      upper = std::min(upper, manhattan(q, c.match));
    }
    if (lower >= upper || lower >= cap_) return std::uint64_t(std::min(upper, cap_));
    CellMatch m;
    if (!search_.anyNearest(q, m, cap_, lower)) return std::uint64_t(cap_);
    certificates_[certificate_count_++ % kCertificates] = Certificate{q, m.key, m.distance};
    return std::uint64_t(m.distance);
  }

  const NodeWord* a_words_;
  CellState v_;
  std::int64_t cap_;
  detail::BrickSettler windows_;
  NearestCellSearch search_;
  ConstAccessor b_cells_;
  Certificate certificates_[kCertificates];  // this brick's walks
  unsigned certificate_count_ = 0;
  std::int64_t floor_ = 0;  // this brick's cells left lie further than its windows reached
};

/** Pieces per chunk: the unit in which threads claim work. */
constexpr std::size_t kPiecesPerChunk = 8;
/**
 * Pieces each thread must have before it is started. A piece costs about 1 µs (a lone cell) to 20 µs (a
 * dense brick), and a thread about 0.25 ms to start: fewer pieces finish sooner on one thread.
 */
constexpr std::size_t kMinPiecesPerThread = 128;

/**
 * d(a, b, v) + d(b, a, v) of eq. 2. Both directions' pieces are cut into chunks that the threads claim one
 * at a time, so a thread whose pieces were cheap takes more. Integer sums, so any split gives the same
 * result.
 */
std::uint64_t bothDirections(const FastOctTree& a, const FastOctTree& b, CellState v, std::int64_t cap,
                             unsigned threads) {
  struct Direction {
    const FastOctTree& from;
    const FastOctTree& to;
    std::vector<Piece> pieces;
  };
  Direction directions[2] = {{a, b, {}}, {b, a, {}}};
  struct Chunk {
    std::size_t direction, first, last;
  };
  std::vector<Chunk> chunks;
  for (std::size_t d = 0; d < 2; ++d) {
    const FastOctTree& from = directions[d].from;
    std::vector<Piece>& pieces = directions[d].pieces;
    collectPieces(from.words(), from.root(), v, pieces);
    for (std::size_t first = 0; first < pieces.size(); first += kPiecesPerChunk)
      chunks.push_back(Chunk{d, first, std::min(first + kPiecesPerChunk, pieces.size())});
  }
  const std::size_t workers = detail::workerCount(
      threads, (directions[0].pieces.size() + directions[1].pieces.size()) / kMinPiecesPerThread);
  std::atomic<std::size_t> next{0};
  std::vector<std::uint64_t> sums(workers, 0);
  detail::runWorkers(workers, [&](std::size_t w) {
    // Chunks are claimed in order, so a thread that reaches the second direction is done with the first.
    // One DirectedSum at a time: with both alive, freeing their buffers left enough at the heap's top for
    // malloc to return it to the system, and every later call paid a page fault per 4 KB (0.13 -> 0.8 ms
    // on maps of 5,700 cells).
    std::unique_ptr<DirectedSum> sum;
    std::size_t direction = 2;
    for (std::size_t c; (c = next.fetch_add(1, std::memory_order_relaxed)) < chunks.size();) {
      const Chunk& chunk = chunks[c];
      const Direction& d = directions[chunk.direction];
      if (chunk.direction != direction) {
        sum.reset();
        sum = std::make_unique<DirectedSum>(d.from, d.to, v, cap);
        direction = chunk.direction;
      }
      sums[w] += sum->pieces(d.pieces.data() + chunk.first, d.pieces.data() + chunk.last);
    }
  });
  std::uint64_t sum = 0;
  for (std::uint64_t s : sums) sum += s;
  return sum;
}

}  // namespace

PsiResult psi(const FastOctTree& a, const FastOctTree& b, const PsiOptions& options) {
  if (a.getGrid() != b.getGrid())
    throw std::invalid_argument(
        "pcl::fot::psi: the maps must share their voxel grid (resolution and origin); got " +
        std::to_string(a.getResolution()) + " m and " + std::to_string(b.getResolution()) + " m cells");
  if (options.cap < 0) throw std::invalid_argument("pcl::fot::psi: the cap must not be negative");
  return detail::sumOverValues(
      options, a.getResolution(),
      [&](CellState v) { return std::make_pair(cellCount(a, v), cellCount(b, v)); },
      [&](CellState v) { return bothDirections(a, b, v, options.cap, options.threads); });
}

}  // namespace fot
}  // namespace pcl
