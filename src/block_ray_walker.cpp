#include "block_ray_walker.h"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define PCL_FOT_X86_LANES 1
#include <immintrin.h>
#endif

namespace pcl {
namespace fot {
namespace detail {
namespace {

#ifdef PCL_FOT_X86_LANES
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

#define PCL_FOT_AVX2 __attribute__((target("avx2"), always_inline)) inline

PCL_FOT_AVX2 __m256i load(const std::int64_t* p) {
  return _mm256_load_si256(reinterpret_cast<const __m256i*>(p));
}
PCL_FOT_AVX2 __m256i load(const std::uint64_t* p) {
  return _mm256_load_si256(reinterpret_cast<const __m256i*>(p));
}
PCL_FOT_AVX2 void store(std::int64_t* p, __m256i v) {
  _mm256_store_si256(reinterpret_cast<__m256i*>(p), v);
}
PCL_FOT_AVX2 void store(std::uint64_t* p, __m256i v) {
  _mm256_store_si256(reinterpret_cast<__m256i*>(p), v);
}
PCL_FOT_AVX2 void storeu(std::uint64_t* p, __m256i v) {
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v);
}
#endif

}  // namespace

BlockRayWalker::BlockRayWalker(const VoxelGrid& grid, const float sensor[3], const float* ends,
                               std::size_t count, Lanes lanes)
    : grid_(grid), sensor_(sensor), ends_(ends), count_(count), path_(Path::Scalar) {
#ifdef PCL_FOT_X86_LANES
  const bool avx2 = lanes != Lanes::Scalar && __builtin_cpu_supports("avx2");
  const bool avx512 =
      lanes == Lanes::Best && avx2 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  path_ = avx512 ? Path::Avx512 : (avx2 ? Path::Avx2 : Path::Scalar);
#else
  (void)lanes;
#endif
  if (!grid.pointToKey(sensor[0], sensor[1], sensor[2], from_)) count_ = 0;  // no ray can start
  for (auto& o : out_) o.resize(kCapacity);
}

std::size_t BlockRayWalker::next() {
  switch (path_) {
    case Path::Avx512:
      return nextAvx512();
    case Path::Avx2:
      return nextAvx2();
    default:
      return nextScalar();
  }
}

void BlockRayWalker::emit(std::size_t& n, std::uint64_t x, std::uint64_t y, std::uint64_t z,
                          std::uint64_t cells) {
  if (n == out_[0].size())
    for (auto& o : out_) o.resize(2 * o.size());
  out_[0][n] = x, out_[1][n] = y, out_[2][n] = z, out_[3][n] = cells;
  ++n;
}

std::size_t BlockRayWalker::nextScalar() {
  std::size_t n = 0;
  while (n < kBatch && next_ray_ < count_) {
    std::uint32_t last[3] = {0, 0, 0};
    std::uint64_t mask = 0;
    cells_ += traceSegment(grid_, sensor_, ends_ + 3 * next_ray_++, [&](const Key& k) {
      const std::uint32_t u[3] = {tree_coord::fromKey(k.x), tree_coord::fromKey(k.y),
                                  tree_coord::fromKey(k.z)};
      const std::uint64_t bit = std::uint64_t(1) << block_cells::bit(u[0] & 3u, u[1] & 3u, u[2] & 3u);
      if (mask != 0 && ((u[0] ^ last[0]) | (u[1] ^ last[1]) | (u[2] ^ last[2])) < 4) {
        mask |= bit;
      } else {
        if (mask != 0) emit(n, last[0], last[1], last[2], mask);
        mask = bit;
      }
      std::copy(u, u + 3, last);
    });
    if (mask != 0) emit(n, last[0], last[1], last[2], mask);
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
      span += std::abs(std::int64_t(to_key[i]) - from_key[i]);
    }
    length_[lane] = ray.length;
    left_[lane] = span_[lane] = span;
    mask_[lane] = std::uint64_t(1) << block_cells::bit(u[0] & 3u, u[1] & 3u, u[2] & 3u);
    live_[lane] = -1;
    return true;
  }
  return false;
}

void BlockRayWalker::finishStep(int l, bool beyond, bool crossed, std::size_t& n) {
  // traceSegment's stops: at the end cell, a few steps past it, or beyond the ray's length.
  const bool at = u_[0][l] == end_[0][l] && u_[1][l] == end_[1][l] && u_[2][l] == end_[2][l];
  const bool done = beyond || (left_[l] <= 0 && (at || left_[l] < -3));
  if (done || crossed) {
    emit(n, std::uint64_t(prev_[0][l]), std::uint64_t(prev_[1][l]), std::uint64_t(prev_[2][l]), mask_[l]);
    mask_[l] = 0;
  }
  if (!done) {
    mask_[l] |= bit_[l];
    return;
  }
  cells_ += std::uint64_t(span_[l] - left_[l]);  // every step but the last visited a cell
  startRay(l);
}

#ifdef PCL_FOT_X86_LANES
namespace {

/** Four lanes' state in registers, loaded from and stored to BlockRayWalker's arrays at lane `base`. */
struct Lanes4 {
  __m256i u0, u1, u2, left, mask;
  __m256d t0, t1, t2;
};

/** What a step leaves for finishStep, in the lanes the vector test flagged. */
struct Flagged {
  int lanes, beyond, crossed;
  __m256i p0, p1, p2, bit;
};

/**
 * One step of traceSegment's loop in four lanes: the same compares, additions and stopping rules per
 * lane, as vector operations. A lane can only be at its end cell once `left` reaches zero, so the vector
 * test is just that and the length; finishStep settles those steps one lane at a time. Stretches of
 * lanes entering another block go to out[0..3] at n.
 */
template <std::size_t L>
PCL_FOT_AVX2 Flagged step4(Lanes4& g, const std::int64_t (&step)[3][L], const double (&tdelta)[3][L],
                           const double* length, const std::int64_t* live, int base,
                           std::uint64_t* const out[4], std::size_t& n) {
  const __m256i one = _mm256_set1_epi64x(1), three = _mm256_set1_epi64x(3);
  // RayWalker::step: x only if its crossing comes strictly first, ties to y, then z.
  const __m256d c01 = _mm256_cmp_pd(g.t0, g.t1, _CMP_LT_OQ), c02 = _mm256_cmp_pd(g.t0, g.t2, _CMP_LT_OQ),
                c12 = _mm256_cmp_pd(g.t1, g.t2, _CMP_LT_OQ);
  const __m256d mx = _mm256_and_pd(c01, c02), my = _mm256_andnot_pd(c01, c12), mxy = _mm256_or_pd(mx, my);
  g.t0 = _mm256_add_pd(g.t0, _mm256_and_pd(mx, _mm256_load_pd(tdelta[0] + base)));
  g.t1 = _mm256_add_pd(g.t1, _mm256_and_pd(my, _mm256_load_pd(tdelta[1] + base)));
  g.t2 = _mm256_add_pd(g.t2, _mm256_andnot_pd(mxy, _mm256_load_pd(tdelta[2] + base)));
  Flagged f;
  f.p0 = g.u0, f.p1 = g.u1, f.p2 = g.u2;
  g.u0 = _mm256_add_epi64(g.u0, _mm256_and_si256(_mm256_castpd_si256(mx), load(step[0] + base)));
  g.u1 = _mm256_add_epi64(g.u1, _mm256_and_si256(_mm256_castpd_si256(my), load(step[1] + base)));
  g.u2 = _mm256_add_epi64(g.u2, _mm256_andnot_si256(_mm256_castpd_si256(mxy), load(step[2] + base)));
  g.left = _mm256_sub_epi64(g.left, one);
  const __m256d exit = _mm256_min_pd(_mm256_min_pd(g.t0, g.t1), g.t2);
  const __m256i beyond = _mm256_castpd_si256(_mm256_cmp_pd(exit, _mm256_load_pd(length + base), _CMP_GT_OQ));
  const __m256i lanes = load(live + base);
  const __m256i flagged = _mm256_and_si256(lanes, _mm256_or_si256(beyond, _mm256_cmpgt_epi64(one, g.left)));
  // The cell's bit, and whether the step entered another block: a coordinate changed above its low bits.
  f.bit = _mm256_sllv_epi64(
      one, _mm256_or_si256(_mm256_and_si256(g.u0, three),
                           _mm256_or_si256(_mm256_slli_epi64(_mm256_and_si256(g.u1, three), 2),
                                           _mm256_slli_epi64(_mm256_and_si256(g.u2, three), 4))));
  const __m256i moved =
      _mm256_or_si256(_mm256_xor_si256(g.u0, f.p0),
                      _mm256_or_si256(_mm256_xor_si256(g.u1, f.p1), _mm256_xor_si256(g.u2, f.p2)));
  const __m256i crossed = _mm256_cmpgt_epi64(moved, three);
  const __m256i walking = _mm256_andnot_si256(flagged, lanes);
  const __m256i emit = _mm256_and_si256(crossed, walking);
  const int m = _mm256_movemask_pd(_mm256_castsi256_pd(emit));
  const __m256i pack = _mm256_load_si256(reinterpret_cast<const __m256i*>(kPack.index[m]));
  storeu(out[0] + n, _mm256_permutevar8x32_epi32(f.p0, pack));
  storeu(out[1] + n, _mm256_permutevar8x32_epi32(f.p1, pack));
  storeu(out[2] + n, _mm256_permutevar8x32_epi32(f.p2, pack));
  storeu(out[3] + n, _mm256_permutevar8x32_epi32(g.mask, pack));
  n += std::size_t(kPack.count[m]);
  const __m256i next = _mm256_blendv_epi8(_mm256_or_si256(g.mask, f.bit), f.bit, emit);
  g.mask = _mm256_blendv_epi8(g.mask, next, walking);
  f.lanes = _mm256_movemask_pd(_mm256_castsi256_pd(flagged));
  f.beyond = _mm256_movemask_pd(_mm256_castsi256_pd(beyond));
  f.crossed = _mm256_movemask_pd(_mm256_castsi256_pd(crossed));
  return f;
}

}  // namespace

/**
 * Walks Groups × 4 lanes, each group's step independent of the others', until a batch is ready or a
 * lane is flagged. One group's step is a chain of dependent operations; two groups fill the pipeline,
 * where there are registers enough for both (AVX-512VL's 32).
 */
template <int Groups>
PCL_FOT_AVX2 std::size_t BlockRayWalker::walkGroups() {
  for (int l = 0; l < 4 * Groups; ++l)
    if (!live_[l]) startRay(l);
  std::uint64_t* const out[4] = {out_[0].data(), out_[1].data(), out_[2].data(), out_[3].data()};
  std::size_t n = 0;
  bool any = false;
  for (int l = 0; l < 4 * Groups; ++l) any |= live_[l] != 0;
  while (n < kBatch && any) {
    Lanes4 g[Groups];
    for (int k = 0; k < Groups; ++k) {
      const int b = 4 * k;
      g[k] = Lanes4{load(u_[0] + b),
                    load(u_[1] + b),
                    load(u_[2] + b),
                    load(left_ + b),
                    load(mask_ + b),
                    _mm256_load_pd(tmax_[0] + b),
                    _mm256_load_pd(tmax_[1] + b),
                    _mm256_load_pd(tmax_[2] + b)};
    }
    Flagged f[Groups];
    int flagged = 0;
    do {
      for (int k = 0; k < Groups; ++k) {
        f[k] = step4(g[k], step_, tdelta_, length_, live_, 4 * k, out, n);
        flagged |= f[k].lanes;
      }
    } while (flagged == 0 && n < kBatch);
    for (int k = 0; k < Groups; ++k) {
      const int b = 4 * k;
      store(u_[0] + b, g[k].u0), store(u_[1] + b, g[k].u1), store(u_[2] + b, g[k].u2);
      store(left_ + b, g[k].left), store(mask_ + b, g[k].mask);
      _mm256_store_pd(tmax_[0] + b, g[k].t0), _mm256_store_pd(tmax_[1] + b, g[k].t1);
      _mm256_store_pd(tmax_[2] + b, g[k].t2);
      if (f[k].lanes == 0) continue;
      store(prev_[0] + b, f[k].p0), store(prev_[1] + b, f[k].p1), store(prev_[2] + b, f[k].p2);
      store(bit_ + b, f[k].bit);
      for (int l = 0; l < 4; ++l)
        if (f[k].lanes >> l & 1) finishStep(b + l, f[k].beyond >> l & 1, f[k].crossed >> l & 1, n);
    }
    any = false;
    for (int l = 0; l < 4 * Groups; ++l) any |= live_[l] != 0;
  }
  return n;
}

__attribute__((target("avx2"))) std::size_t BlockRayWalker::nextAvx2() {
  return walkGroups<1>();
}

__attribute__((target("avx2,avx512f,avx512vl"))) std::size_t BlockRayWalker::nextAvx512() {
  return walkGroups<2>();
}
#else
std::size_t BlockRayWalker::nextAvx2() {
  return nextScalar();
}
std::size_t BlockRayWalker::nextAvx512() {
  return nextScalar();
}
#endif

}  // namespace detail
}  // namespace fot
}  // namespace pcl
