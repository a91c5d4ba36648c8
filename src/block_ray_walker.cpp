#include "block_ray_walker.h"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define PCL_FOT_AVX2_PATH 1
#include <immintrin.h>
#endif

namespace pcl {
namespace fot {
namespace detail {
namespace {

/** Bit of the cell at tree coordinates u in its 4×4×4 block: 8 × leaf octant + cell octant. */
inline unsigned blockBit(const std::uint32_t u[3]) {
  return 8 * tree_coord::octant(u[0], u[1], u[2], 2) + tree_coord::octant(u[0], u[1], u[2], 1);
}

#ifdef PCL_FOT_AVX2_PATH
/** For each 4-bit lane mask, the vpermd indices that move the selected 64-bit lanes to the front. */
struct PackTable {
  alignas(32) std::int32_t index[16][8];
  std::int32_t count[16];
  constexpr PackTable() : index(), count() {
    for (int m = 0; m < 16; ++m) {
      int j = 0;
      for (int lane = 0; lane < 4; ++lane)
        if (m >> lane & 1) {
          index[m][2 * j] = 2 * lane;
          index[m][2 * j + 1] = 2 * lane + 1;
          ++j;
        }
      count[m] = j;
    }
  }
};
constexpr PackTable kPack;

__attribute__((target("avx2"), always_inline)) inline __m256i load(const std::int64_t* p) {
  return _mm256_load_si256(reinterpret_cast<const __m256i*>(p));
}
__attribute__((target("avx2"), always_inline)) inline void store(std::int64_t* p, __m256i v) {
  _mm256_store_si256(reinterpret_cast<__m256i*>(p), v);
}
__attribute__((target("avx2"), always_inline)) inline void storeu(std::uint64_t* p, __m256i v) {
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v);
}
#endif

}  // namespace

BlockRayWalker::BlockRayWalker(const VoxelGrid& grid, const float sensor[3], const float* ends,
                               std::size_t count, Lanes lanes)
    : grid_(grid), sensor_(sensor), ends_(ends), count_(count) {
#ifdef PCL_FOT_AVX2_PATH
  avx2_ = lanes == Lanes::Best && __builtin_cpu_supports("avx2");
#else
  avx2_ = false;
  (void)lanes;
#endif
  if (!grid.pointToKey(sensor[0], sensor[1], sensor[2], from_)) count_ = 0;  // no ray can start
  for (auto& o : out_) o.resize(kCapacity);
}

std::uint64_t BlockRayWalker::cellCount() const {
  std::uint64_t n = started_cells_ + scalar_cells_;
  for (int l = 0; l < kLanes; ++l) n -= std::uint64_t(walked_[l]);
  return n;
}

std::size_t BlockRayWalker::next() {
  return avx2_ ? nextAvx2() : nextScalar();
}

void BlockRayWalker::emit(std::size_t& n, std::uint64_t bx, std::uint64_t by, std::uint64_t bz,
                          std::uint64_t cells) {
  if (n == out_[0].size())
    for (auto& o : out_) o.resize(2 * o.size());
  out_[0][n] = bx, out_[1][n] = by, out_[2][n] = bz, out_[3][n] = cells;
  ++n;
}

std::size_t BlockRayWalker::nextScalar() {
  std::size_t n = 0;
  while (n < kBatch && next_ray_ < count_) {
    std::uint32_t block[3] = {0, 0, 0};
    std::uint64_t mask = 0;
    scalar_cells_ += traceSegment(grid_, sensor_, ends_ + 3 * next_ray_++, [&](const Key& k) {
      const std::uint32_t u[3] = {tree_coord::fromKey(k.x), tree_coord::fromKey(k.y),
                                  tree_coord::fromKey(k.z)};
      const std::uint64_t bit = std::uint64_t(1) << blockBit(u);
      if (mask != 0 && (u[0] >> 2) == block[0] && (u[1] >> 2) == block[1] && (u[2] >> 2) == block[2]) {
        mask |= bit;
        return;
      }
      if (mask != 0) emit(n, block[0], block[1], block[2], mask);
      block[0] = u[0] >> 2, block[1] = u[1] >> 2, block[2] = u[2] >> 2;
      mask = bit;
    });
    if (mask != 0) emit(n, block[0], block[1], block[2], mask);
  }
  return n;
}

bool BlockRayWalker::startRay(int lane) {
  live_[lane] = 0;
  while (next_ray_ < count_) {
    const float* end = ends_ + 3 * next_ray_++;
    Key to;
    if (!grid_.pointToKey(end[0], end[1], end[2], to) || to == from_) continue;  // as traceSegment
    const RaySetup ray = setupRay(grid_, sensor_, end);
    const DdaStart s = ddaStart(grid_, from_, ray.origin, ray.direction);
    const std::int32_t from_key[3] = {from_.x, from_.y, from_.z}, to_key[3] = {to.x, to.y, to.z};
    std::uint32_t u[3];
    std::int64_t span = 0;
    for (int i = 0; i < 3; ++i) {
      u[i] = tree_coord::fromKey(from_key[i]);
      u_[i][lane] = u[i];
      end_[i][lane] = tree_coord::fromKey(to_key[i]);
      step_[i][lane] = s.step[i];
      tmax_[i][lane] = s.tmax[i];
      tdelta_[i][lane] = s.tdelta[i];
      block_[i][lane] = u[i] >> 2;
      span += std::abs(std::int64_t(to_key[i]) - from_key[i]);
    }
    length_[lane] = ray.length;
    left_[lane] = span;
    mask_[lane] = std::uint64_t(1) << blockBit(u);
    live_[lane] = -1;
    ++started_cells_;
    return true;
  }
  return false;
}

#ifdef PCL_FOT_AVX2_PATH
/**
 * traceSegment's loop, four rays at a time: the same compares, additions and stopping rules per lane, as
 * vector operations. A lane whose ray ends hands out its last stretch and takes the next ray.
 */
__attribute__((target("avx2"))) std::size_t BlockRayWalker::nextAvx2() {
  for (int l = 0; l < kLanes; ++l)
    if (!live_[l]) startRay(l);
  const __m256i one = _mm256_set1_epi64x(1), two = _mm256_set1_epi64x(2), minus3 = _mm256_set1_epi64x(-3);

  std::size_t n = 0;
  for (;;) {
    if (!(live_[0] | live_[1] | live_[2] | live_[3])) break;
    __m256i u0 = load(u_[0]), u1 = load(u_[1]), u2 = load(u_[2]);
    const __m256i s0 = load(step_[0]), s1 = load(step_[1]), s2 = load(step_[2]);
    const __m256i e0 = load(end_[0]), e1 = load(end_[1]), e2 = load(end_[2]);
    __m256d t0 = _mm256_load_pd(tmax_[0]), t1 = _mm256_load_pd(tmax_[1]), t2 = _mm256_load_pd(tmax_[2]);
    const __m256d d0 = _mm256_load_pd(tdelta_[0]), d1 = _mm256_load_pd(tdelta_[1]),
                  d2 = _mm256_load_pd(tdelta_[2]);
    const __m256d length = _mm256_load_pd(length_);
    const __m256i live = load(live_);
    __m256i left = load(left_), b0 = load(block_[0]), b1 = load(block_[1]), b2 = load(block_[2]);
    __m256i mask = load(reinterpret_cast<const std::int64_t*>(mask_)), walked = load(walked_);
    int done_lanes = 0;
    while (n < kBatch) {
      // RayWalker::step: x only if its crossing comes strictly first, ties to y, then z.
      const __m256d c01 = _mm256_cmp_pd(t0, t1, _CMP_LT_OQ), c02 = _mm256_cmp_pd(t0, t2, _CMP_LT_OQ),
                    c12 = _mm256_cmp_pd(t1, t2, _CMP_LT_OQ);
      const __m256d mx = _mm256_and_pd(c01, c02), my = _mm256_andnot_pd(c01, c12);
      const __m256d mz = _mm256_andnot_pd(_mm256_or_pd(mx, my), _mm256_castsi256_pd(_mm256_set1_epi64x(-1)));
      t0 = _mm256_add_pd(t0, _mm256_and_pd(mx, d0));
      t1 = _mm256_add_pd(t1, _mm256_and_pd(my, d1));
      t2 = _mm256_add_pd(t2, _mm256_and_pd(mz, d2));
      u0 = _mm256_add_epi64(u0, _mm256_and_si256(_mm256_castpd_si256(mx), s0));
      u1 = _mm256_add_epi64(u1, _mm256_and_si256(_mm256_castpd_si256(my), s1));
      u2 = _mm256_add_epi64(u2, _mm256_and_si256(_mm256_castpd_si256(mz), s2));
      left = _mm256_sub_epi64(left, one);
      // traceSegment's stops: at the end cell, a few steps past it, or beyond the ray's length.
      const __m256i at =
          _mm256_and_si256(_mm256_cmpeq_epi64(u0, e0),
                           _mm256_and_si256(_mm256_cmpeq_epi64(u1, e1), _mm256_cmpeq_epi64(u2, e2)));
      const __m256d exit = _mm256_min_pd(_mm256_min_pd(t0, t1), t2);
      const __m256i beyond = _mm256_castpd_si256(_mm256_cmp_pd(exit, length, _CMP_GT_OQ));
      const __m256i done = _mm256_and_si256(
          live, _mm256_or_si256(at, _mm256_or_si256(_mm256_cmpgt_epi64(minus3, left), beyond)));
      const __m256i visit = _mm256_andnot_si256(done, live);
      // The cell's block and bit; a lane entering another block hands out its stretch.
      const __m256i n0 = _mm256_srli_epi64(u0, 2), n1 = _mm256_srli_epi64(u1, 2),
                    n2 = _mm256_srli_epi64(u2, 2);
      const __m256i same =
          _mm256_and_si256(_mm256_cmpeq_epi64(n0, b0),
                           _mm256_and_si256(_mm256_cmpeq_epi64(n1, b1), _mm256_cmpeq_epi64(n2, b2)));
      const __m256i emit = _mm256_andnot_si256(same, visit);
      const __m256i lo = _mm256_or_si256(_mm256_and_si256(u0, one),
                                         _mm256_or_si256(_mm256_slli_epi64(_mm256_and_si256(u1, one), 1),
                                                         _mm256_slli_epi64(_mm256_and_si256(u2, one), 2)));
      const __m256i hi = _mm256_or_si256(_mm256_slli_epi64(_mm256_and_si256(u0, two), 2),
                                         _mm256_or_si256(_mm256_slli_epi64(_mm256_and_si256(u1, two), 3),
                                                         _mm256_slli_epi64(_mm256_and_si256(u2, two), 4)));
      const __m256i bit = _mm256_sllv_epi64(one, _mm256_or_si256(lo, hi));
      const int m = _mm256_movemask_pd(_mm256_castsi256_pd(emit));
      const __m256i pack = _mm256_load_si256(reinterpret_cast<const __m256i*>(kPack.index[m]));
      storeu(out_[0].data() + n, _mm256_permutevar8x32_epi32(b0, pack));
      storeu(out_[1].data() + n, _mm256_permutevar8x32_epi32(b1, pack));
      storeu(out_[2].data() + n, _mm256_permutevar8x32_epi32(b2, pack));
      storeu(out_[3].data() + n, _mm256_permutevar8x32_epi32(mask, pack));
      n += std::size_t(kPack.count[m]);
      b0 = _mm256_blendv_epi8(b0, n0, emit);
      b1 = _mm256_blendv_epi8(b1, n1, emit);
      b2 = _mm256_blendv_epi8(b2, n2, emit);
      mask = _mm256_blendv_epi8(_mm256_or_si256(mask, _mm256_and_si256(bit, visit)), bit, emit);
      walked = _mm256_add_epi64(walked, visit);
      done_lanes = _mm256_movemask_pd(_mm256_castsi256_pd(done));
      if (done_lanes != 0) break;
    }
    store(u_[0], u0), store(u_[1], u1), store(u_[2], u2);
    _mm256_store_pd(tmax_[0], t0), _mm256_store_pd(tmax_[1], t1), _mm256_store_pd(tmax_[2], t2);
    store(left_, left), store(block_[0], b0), store(block_[1], b1), store(block_[2], b2);
    store(reinterpret_cast<std::int64_t*>(mask_), mask), store(walked_, walked);
    for (int l = 0; l < kLanes; ++l)
      if (done_lanes >> l & 1) {
        emit(n, std::uint64_t(block_[0][l]), std::uint64_t(block_[1][l]), std::uint64_t(block_[2][l]),
             mask_[l]);
        startRay(l);
      }
    if (n >= kBatch) break;
  }
  return n;
}
#else
std::size_t BlockRayWalker::nextAvx2() {
  return nextScalar();
}
#endif

}  // namespace detail
}  // namespace fot
}  // namespace pcl
