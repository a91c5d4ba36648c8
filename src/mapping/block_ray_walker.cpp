#include "mapping/block_ray_walker.h"

#include <cstdlib>
#include <limits>

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

namespace {
// A word's bits per axis: the cell's two low bits in the block_cells bit, then 19 bits of its block.
constexpr std::uint64_t kAxisBits[3] = {0x3u | std::uint64_t(0x7FFFF) << 6,
                                        0xCu | std::uint64_t(0x7FFFF) << 25,
                                        0x30u | std::uint64_t(0x7FFFF) << 44};
// Fields count from 2^20 cells below the sensor's aligned cube: room for rays both ways.
constexpr std::uint64_t kBias = std::uint64_t(1) << 20;
}  // namespace

BlockRayWalker::BlockRayWalker(const CellGrid& grid, const float sensor[3], const float* ends,
                               std::size_t count, Lanes lanes)
    : BlockRayWalker(grid, sensor, ends, nullptr, count, lanes) {}

BlockRayWalker::BlockRayWalker(const CellGrid& grid, const float sensor[3], const float* ends,
                               const double* cuts, std::size_t count, Lanes lanes)
    : grid_(grid), sensor_(sensor), ends_(ends), cuts_(cuts), count_(count), path_(Path::Scalar) {
#ifdef PCL_FOT_X86_LANES
  const bool avx2 = lanes != Lanes::Scalar && __builtin_cpu_supports("avx2");
  const bool avx512 =
      lanes == Lanes::Best && avx2 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  path_ = avx512 ? Path::Avx512 : (avx2 ? Path::Avx2 : Path::Scalar);
#else
  (void)lanes;
#endif
  if (!grid.pointToKey(sensor[0], sensor[1], sensor[2], from_)) count_ = 0;  // no ray can start
  const TreeCoord u(from_);
  for (int a = 0; a < 3; ++a) {
    origin_[a] = (u[a] & ~((std::uint32_t(1) << kAlign) - 1)) - std::uint32_t(kBias);
    block_base_[a] = origin_[a] / 4;
  }
  start_ = word(u);
  for (auto& o : out_) o.resize(kCapacity);
}

bool BlockRayWalker::reaches(const Key& from, const Key& to) {
  return std::abs(std::int64_t(to.x) - from.x) <= kReach && std::abs(std::int64_t(to.y) - from.y) <= kReach &&
         std::abs(std::int64_t(to.z) - from.z) <= kReach;
}

std::uint64_t BlockRayWalker::word(const TreeCoord& c) const {
  const std::uint64_t f[3] = {c[0] - origin_[0], c[1] - origin_[1], c[2] - origin_[2]};
  return (f[0] & 3u) | (f[1] & 3u) << 2 | (f[2] & 3u) << 4 | (f[0] >> 2) << 6 | (f[1] >> 2) << 25 |
         (f[2] >> 2) << 44;
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

void BlockRayWalker::emit(std::size_t& n, std::uint64_t cell, std::uint64_t cells) {
  if (n == out_[0].size())
    for (auto& o : out_) o.resize(2 * o.size());
  out_[0][n] = cell, out_[1][n] = cells;
  ++n;
}

std::size_t BlockRayWalker::nextScalar() {
  std::size_t n = 0;
  while (n < kBatch && next_ray_ < count_) {
    std::uint64_t last = 0, mask = 0;
    cells_ += traceSegment(grid_, sensor_, ends_ + 3 * next_ray_++, [&](const Key& k) {
      const std::uint64_t w = word(TreeCoord(k));
      if (mask != 0 && (w ^ last) >> 6 != 0) {
        emit(n, last, mask);
        mask = 0;
      }
      mask |= std::uint64_t(1) << (w & 63u);
      last = w;
    });
    if (mask != 0) emit(n, last, mask);
  }
  return n;
}

void BlockRayWalker::prepare() {
  // Walks start at the sensor's cell, even where rounding puts the first crossing before it.
  constexpr double kNoCut = -std::numeric_limits<double>::infinity();
  ready_next_ = ready_count_ = 0;
  double tmax[3][kReady], tdelta[3][kReady], cut[kReady];
  std::int64_t skip[3][kReady] = {};
  int step[3][kReady];
  while (ready_count_ < kReady && next_ray_ < count_) {
    const std::size_t index = next_ray_++;
    const float* end = ends_ + 3 * index;
    Key to;
    if (!grid_.pointToKey(end[0], end[1], end[2], to) || to == from_) continue;  // as traceSegment
    const RaySetup ray = setupRay(grid_, sensor_, end);
    const DdaStart s = ddaStart(grid_, from_, ray.origin, ray.direction);
    const int r = ready_count_++;
    Ready& ready = ready_[r];
    const std::int32_t from_key[3] = {from_.x, from_.y, from_.z}, to_key[3] = {to.x, to.y, to.z};
    ready.span = 0;
    for (int a = 0; a < 3; ++a) {
      // +1 is the axis's lowest bit; -1 all of its bits, with the carry running out of the top.
      ready.inc[a] = s.step[a] > 0 ? std::int64_t(kAxisBits[a] & (~kAxisBits[a] + 1))
                                   : (s.step[a] < 0 ? std::int64_t(kAxisBits[a]) : 0);
      tmax[a][r] = s.tmax[a];
      tdelta[a][r] = ready.tdelta[a] = s.tdelta[a];
      step[a][r] = s.step[a];
      ready.span += std::abs(std::int64_t(to_key[a]) - from_key[a]);
    }
    ready.end = std::int64_t(word(TreeCoord(to)));
    ready.length = ray.length;
    cut[r] = cuts_ && cuts_[index] > 0.0 ? cuts_[index] : kNoCut;
  }
  for (int r = ready_count_; r < kReady; ++r) {
    cut[r] = kNoCut;
    for (int a = 0; a < 3; ++a) tmax[a][r] = tdelta[a][r] = 0.0;
  }
  if (cuts_) forward(tmax, tdelta, cut, skip);
  for (int r = 0; r < ready_count_; ++r) {
    Ready& ready = ready_[r];
    const std::int64_t skipped = skip[0][r] + skip[1][r] + skip[2][r];
    const std::int32_t at[3] = {from_.x + std::int32_t(step[0][r] * skip[0][r]),
                                from_.y + std::int32_t(step[1][r] * skip[1][r]),
                                from_.z + std::int32_t(step[2][r] * skip[2][r])};
    ready.cell = skipped ? std::int64_t(word(TreeCoord(Key{at[0], at[1], at[2]}))) : std::int64_t(start_);
    ready.left = ready.span - skipped;
    for (int a = 0; a < 3; ++a) ready.tmax[a] = tmax[a][r];
    skipped_ += std::uint64_t(skipped);
  }
}

bool BlockRayWalker::startRay(int lane) {
  live_[lane] = 0;
  if (ready_next_ == ready_count_) prepare();
  if (ready_next_ == ready_count_) return false;
  const Ready& ready = ready_[ready_next_++];
  for (int a = 0; a < 3; ++a) {
    inc_[a][lane] = ready.inc[a];
    tmax_[a][lane] = ready.tmax[a];
    tdelta_[a][lane] = ready.tdelta[a];
  }
  cell_[lane] = ready.cell;
  end_[lane] = ready.end;
  length_[lane] = ready.length;
  span_[lane] = ready.span;
  left_[lane] = ready.left;
  mask_[lane] = std::uint64_t(1) << (ready.cell & 63u);
  live_[lane] = -1;
  return true;
}

void BlockRayWalker::finishStep(int l, bool beyond, bool crossed, std::size_t& n) {
  // traceSegment's stops: at the end cell, a few steps past it, or beyond the ray's length.
  const bool done = beyond || (left_[l] <= 0 && (cell_[l] == end_[l] || left_[l] < -3));
  if (done || crossed) {
    emit(n, std::uint64_t(prev_[l]), mask_[l]);
    mask_[l] = 0;
  }
  if (!done) {
    mask_[l] |= bit_[l];
    return;
  }
  cells_ += std::uint64_t(span_[l] - left_[l]);  // every step but the last visited a cell
  startRay(l);
}

void BlockRayWalker::forward(double (&tmax)[3][kReady], const double (&tdelta)[3][kReady],
                             const double (&cut)[kReady], std::int64_t (&skip)[3][kReady]) const {
#ifdef PCL_FOT_X86_LANES
  if (path_ != Path::Scalar) return forwardAvx2(tmax, tdelta, cut, skip);
#endif
  for (int r = 0; r < kReady; ++r)
    for (int a = 0; a < 3; ++a)
      for (; tmax[a][r] < cut[r]; ++skip[a][r]) tmax[a][r] += tdelta[a][r];
}

#ifdef PCL_FOT_X86_LANES
/** forward's additions, the rays' axes side by side in vector lanes: 6 independent chains. */
__attribute__((target("avx2"))) void BlockRayWalker::forwardAvx2(double (&tmax)[3][kReady],
                                                                 const double (&tdelta)[3][kReady],
                                                                 const double (&cut)[kReady],
                                                                 std::int64_t (&skip)[3][kReady]) {
  static_assert(kReady == 8, "two groups of four rays");
  __m256d t[6], d[6];
  __m256i n[6];
  const __m256d c[2] = {_mm256_loadu_pd(cut), _mm256_loadu_pd(cut + 4)};
  for (int j = 0; j < 6; ++j) {
    t[j] = _mm256_loadu_pd(tmax[j / 2] + 4 * (j % 2));
    d[j] = _mm256_loadu_pd(tdelta[j / 2] + 4 * (j % 2));
    n[j] = _mm256_setzero_si256();
  }
  for (int any = 1; any;) {
    any = 0;
    for (int j = 0; j < 6; ++j) {
      const __m256d m = _mm256_cmp_pd(t[j], c[j % 2], _CMP_LT_OQ);
      t[j] = _mm256_add_pd(t[j], _mm256_and_pd(m, d[j]));
      n[j] = _mm256_sub_epi64(n[j], _mm256_castpd_si256(m));
      any |= _mm256_movemask_pd(m);
    }
  }
  for (int j = 0; j < 6; ++j) {
    _mm256_storeu_pd(tmax[j / 2] + 4 * (j % 2), t[j]);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(skip[j / 2] + 4 * (j % 2)), n[j]);
  }
}

namespace {

/** Four lanes' state in registers, loaded from and stored to BlockRayWalker's arrays at lane `base`. */
struct Lanes4 {
  __m256i cell, left, mask;
  __m256d t0, t1, t2;
};

/** What a step leaves for finishStep, in the lanes the vector test flagged. */
struct Flagged {
  int lanes, beyond, crossed;
  __m256i prev, bit;
};

/**
 * One step of traceSegment's loop in four lanes: the same compares, additions and stopping rules per
 * lane, as vector operations. A lane can only be at its end cell once `left` reaches zero, so the vector
 * test is just that and the length; finishStep settles those steps one lane at a time. Stretches of
 * lanes entering another block go to out[0..1] at n.
 */
template <std::size_t L>
PCL_FOT_AVX2 Flagged step4(Lanes4& g, const std::int64_t (&inc)[3][L], const double (&tdelta)[3][L],
                           const double* length, const std::int64_t* live, int base,
                           std::uint64_t* const out[2], std::size_t& n) {
  const __m256i one = _mm256_set1_epi64x(1), low = _mm256_set1_epi64x(63);
  // RayWalker::step: x only if its crossing comes strictly first, ties to y, then z.
  const __m256d c01 = _mm256_cmp_pd(g.t0, g.t1, _CMP_LT_OQ), c02 = _mm256_cmp_pd(g.t0, g.t2, _CMP_LT_OQ),
                c12 = _mm256_cmp_pd(g.t1, g.t2, _CMP_LT_OQ);
  const __m256d mx = _mm256_and_pd(c01, c02), my = _mm256_andnot_pd(c01, c12), mxy = _mm256_or_pd(mx, my);
  g.t0 = _mm256_add_pd(g.t0, _mm256_and_pd(mx, _mm256_load_pd(tdelta[0] + base)));
  g.t1 = _mm256_add_pd(g.t1, _mm256_and_pd(my, _mm256_load_pd(tdelta[1] + base)));
  g.t2 = _mm256_add_pd(g.t2, _mm256_andnot_pd(mxy, _mm256_load_pd(tdelta[2] + base)));
  // The step in the word: fill the other bits, add, and keep the stepping axis's bits of the sum.
  const __m256i others = _mm256_castpd_si256(_mm256_blendv_pd(
      _mm256_blendv_pd(_mm256_castsi256_pd(_mm256_set1_epi64x(std::int64_t(~kAxisBits[2]))),
                       _mm256_castsi256_pd(_mm256_set1_epi64x(std::int64_t(~kAxisBits[1]))), my),
      _mm256_castsi256_pd(_mm256_set1_epi64x(std::int64_t(~kAxisBits[0]))), mx));
  const __m256i add = _mm256_castpd_si256(
      _mm256_blendv_pd(_mm256_blendv_pd(_mm256_load_pd(reinterpret_cast<const double*>(inc[2] + base)),
                                        _mm256_load_pd(reinterpret_cast<const double*>(inc[1] + base)), my),
                       _mm256_load_pd(reinterpret_cast<const double*>(inc[0] + base)), mx));
  Flagged f;
  f.prev = g.cell;
  const __m256i sum = _mm256_add_epi64(_mm256_or_si256(g.cell, others), add);
  g.cell = _mm256_or_si256(_mm256_andnot_si256(others, sum), _mm256_and_si256(others, g.cell));
  g.left = _mm256_sub_epi64(g.left, one);
  const __m256d exit = _mm256_min_pd(_mm256_min_pd(g.t0, g.t1), g.t2);
  const __m256i beyond = _mm256_castpd_si256(_mm256_cmp_pd(exit, _mm256_load_pd(length + base), _CMP_GT_OQ));
  const __m256i lanes = load(live + base);
  const __m256i flagged = _mm256_and_si256(lanes, _mm256_or_si256(beyond, _mm256_cmpgt_epi64(one, g.left)));
  // The cell's bit, and whether the step entered another block: the word changed above its low bits.
  f.bit = _mm256_sllv_epi64(one, _mm256_and_si256(g.cell, low));
  const __m256i crossed = _mm256_cmpgt_epi64(_mm256_xor_si256(g.cell, f.prev), low);
  const __m256i walking = _mm256_andnot_si256(flagged, lanes);
  const __m256i emit = _mm256_and_si256(crossed, walking);
  const int m = _mm256_movemask_pd(_mm256_castsi256_pd(emit));
  const __m256i pack = _mm256_load_si256(reinterpret_cast<const __m256i*>(kPack.index[m]));
  storeu(out[0] + n, _mm256_permutevar8x32_epi32(f.prev, pack));
  storeu(out[1] + n, _mm256_permutevar8x32_epi32(g.mask, pack));
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
  std::uint64_t* const out[2] = {out_[0].data(), out_[1].data()};
  std::size_t n = 0;
  bool any = false;
  for (int l = 0; l < 4 * Groups; ++l) any |= live_[l] != 0;
  while (n < kBatch && any) {
    Lanes4 g[Groups];
    for (int k = 0; k < Groups; ++k) {
      const int b = 4 * k;
      g[k] = Lanes4{load(cell_ + b),
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
        f[k] = step4(g[k], inc_, tdelta_, length_, live_, 4 * k, out, n);
        flagged |= f[k].lanes;
      }
    } while (flagged == 0 && n < kBatch);
    for (int k = 0; k < Groups; ++k) {
      const int b = 4 * k;
      store(cell_ + b, g[k].cell), store(left_ + b, g[k].left), store(mask_ + b, g[k].mask);
      _mm256_store_pd(tmax_[0] + b, g[k].t0), _mm256_store_pd(tmax_[1] + b, g[k].t1);
      _mm256_store_pd(tmax_[2] + b, g[k].t2);
      if (f[k].lanes == 0) continue;
      store(prev_ + b, f[k].prev), store(bit_ + b, f[k].bit);
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
