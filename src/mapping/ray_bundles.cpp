#include "mapping/ray_bundles.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <pcl_fot/detail/worker_threads.h>
#include <pcl_fot/mapping/ray_traversal.h>
#include <pcl_fot/tree/tree_coord.h>

namespace pcl {
namespace fot {
namespace detail {
namespace {

/**
 * How far, in cells, a ray must clear a cell's faces to certainly pass it. The walk's crossings stray from
 * the exact ones of its float ray by its half-cell float and its repeated additions: below 1e-3 of a cell
 * over the 2^21 steps a walk may take.
 */
constexpr double kMargin = 1.0 / 128;
/** A bundle's width in fine bins; fine bins are sized to hold about a quarter of a ray each. */
constexpr double kBundleBins = 16;
/**
 * A face is swept where its rays are at least this many to a cell's width at their mean depth: sparser,
 * few cells are passed by many rays, and the sweep costs more than it saves (laser scans of rooms at
 * 5 cm, about one ray to a cell's width: a third of the cells skipped, 5-10% slower in all).
 */
constexpr double kMinRaysAcross = 2.0;
/** Every this many rays make the sample that judges the faces. */
constexpr std::size_t kSampleEvery = 16;
/** Bundles a thread takes at least. */
constexpr std::size_t kBundlesPerBand = 256;
/** Cells a layer's certainty map may hold, per ray of the face: bounds the sweep's memory. */
constexpr std::size_t kLayerCellsPerRay = 64;

/**
 * The deepest end among a face's rays, per bin of their tangent coordinates (p, q), and in a pyramid of
 * coarser bins: whether some ray in a rectangle ends deeper than a layer takes one to nine look-ups.
 */
class EndDepths {
 public:
  /** Starts anew over nx × ny fine bins of `width` from (p0, q0), no ray in them; keeps the buffers. */
  void reset(double p0, double q0, double width, std::size_t nx, std::size_t ny) {
    p0_ = p0, q0_ = q0, width_ = width, inv_width_ = 1.0 / width;
    used_ = 0;
    push(nx, ny, 1.0);
  }

  void add(double p, double q, double depth) {
    Level& l = levels_[0];
    const std::size_t x = std::min(std::size_t((p - p0_) / width_), l.nx - 1);
    const std::size_t y = std::min(std::size_t((q - q0_) / width_), l.ny - 1);
    // As a float no deeper than the ray's end: the test stays on the safe side.
    float f = float(depth);
    if (double(f) > depth) f = std::nextafter(f, -1.0f);
    float& d = l.depth[y * l.nx + x];
    d = std::max(d, f);
  }

  double binWidth() const { return width_; }

  void build() {
    while (levels_[used_ - 1].nx > 1 || levels_[used_ - 1].ny > 1) {
      const std::size_t nx = levels_[used_ - 1].nx, ny = levels_[used_ - 1].ny;
      push((nx + 1) / 2, (ny + 1) / 2, 0.5 * levels_[used_ - 1].scale);
      const Level& f = levels_[used_ - 2];
      Level& c = levels_[used_ - 1];
      for (std::size_t y = 0; y < f.ny; ++y)
        for (std::size_t x = 0; x < f.nx; ++x) {
          float& d = c.depth[(y / 2) * c.nx + x / 2];
          d = std::max(d, f.depth[y * f.nx + x]);
        }
    }
  }

  /**
   * Whether a ray that lies in [pa, pb] x [qa, qb] ends deeper than `depth`, judged by the coarsest bins
   * of which one fits wholly inside the part of the rectangle that the bins cover.
   */
  bool deeper(double pa, double pb, double qa, double qb, double depth) const {
    const Level& fine = levels_[0];
    // In fine bins from the grid's corner, clipped to the grid.
    const double xa = std::max((pa - p0_) * inv_width_, 0.0),
                 xb = std::min((pb - p0_) * inv_width_, double(fine.nx));
    const double ya = std::max((qa - q0_) * inv_width_, 0.0),
                 yb = std::min((qb - q0_) * inv_width_, double(fine.ny));
    const double span = std::min(xb - xa, yb - ya);
    if (!(span >= 2.0)) return false;
    // The level whose bins are at most half the span: the exponent of span / 2.
    std::uint64_t bits;
    const double half = 0.5 * span;
    std::memcpy(&bits, &half, sizeof bits);
    const unsigned level = std::min(unsigned(bits >> 52) - 1023u, unsigned(used_) - 1);
    const Level& l = levels_[level];
    const double scale = l.scale;
    const std::size_t x0 = ceilIndex(xa * scale), x1 = std::min(std::size_t(xb * scale), l.nx);
    const std::size_t y0 = ceilIndex(ya * scale), y1 = std::min(std::size_t(yb * scale), l.ny);
    for (std::size_t y = y0; y < y1; ++y)
      for (std::size_t x = x0; x < x1; ++x)
        if (double(l.depth[y * l.nx + x]) > depth) return true;
    return false;
  }

 private:
  struct Level {
    std::size_t nx = 0, ny = 0;
    std::vector<float> depth;
    double scale = 1.0;  // its bins per fine bin
  };
  static std::size_t ceilIndex(double x) {
    const std::size_t i = std::size_t(x);
    return i + std::size_t(double(i) < x);
  }
  /** Takes the next level, its bins empty; a level of an earlier scan lends its buffer. */
  void push(std::size_t nx, std::size_t ny, double scale) {
    if (used_ == levels_.size()) levels_.emplace_back();
    Level& l = levels_[used_++];
    l.nx = nx, l.ny = ny, l.scale = scale;
    l.depth.assign(nx * ny, -1.0f);
  }

  double p0_ = 0.0, q0_ = 0.0, width_ = 1.0, inv_width_ = 1.0;
  std::vector<Level> levels_;  // the first used_ are this face's
  std::size_t used_ = 0;
};

/** The axis of a direction's largest component: its face is that axis's, on the side it points to. */
unsigned faceAxis(const double (&d)[3]) {
  unsigned a = 0;
  for (unsigned b = 1; b < 3; ++b)
    if (std::fabs(d[b]) > std::fabs(d[a])) a = b;
  return a;
}

/** A sample of a face's rays: their count, their tangent box and their mean depth. */
struct FaceSample {
  std::size_t n = 0;
  double depth = 0.0, p0 = 1.0, p1 = -1.0, q0 = 1.0, q1 = -1.0;
  bool worth = false;

  void add(const double (&d)[3], unsigned a) {
    const double along = std::fabs(d[a]), p = d[(a + 1) % 3] / along, q = d[(a + 2) % 3] / along;
    p0 = std::min(p0, p), p1 = std::max(p1, p), q0 = std::min(q0, q), q1 = std::max(q1, q);
    depth += along;
    ++n;
  }

  /** Rays across a cell's width at the mean depth, if the sample is every `every`-th ray. */
  double raysAcrossACell(double res, std::size_t every) const {
    if (n < 16) return 0.0;
    const double spacing = std::sqrt(std::max((p1 - p0) * (q1 - q0), 1e-12) / double(n * every));
    return res / (depth / double(n)) / spacing;
  }
};

/** A ray of a face: its direction's tangent coordinates, its end's depth along the face's axis. */
struct FaceRay {
  double p, q, depth;
  double axis;  // |direction| along the face's axis: depth per unit of the walk's distance
  std::uint32_t ray;
};

/** Rays of a face that one thread set up, in the rays' order, and the box of their tangent coordinates. */
struct FaceRays {
  std::vector<FaceRay> rays;
  double p0 = 0.0, p1 = 0.0, q0 = 0.0, q1 = 0.0;
};

/** The rays whose direction's largest component is `axis`, pointing `sign`: a part a thread. */
struct Face {
  unsigned axis, u, v;
  int sign;
  std::vector<FaceRays> parts;

  std::size_t size() const {
    std::size_t n = 0;
    for (const FaceRays& p : parts) n += p.rays.size();
    return n;
  }
};

/** A bundle: rays of nearby directions, the box of their tangent coordinates, and how far it got. */
struct Bundle {
  double p0 = std::numeric_limits<double>::max(), p1 = -std::numeric_limits<double>::max();
  double q0 = std::numeric_limits<double>::max(), q1 = -std::numeric_limits<double>::max();
  double deepest = 0.0;                           // end depth of its deepest ray
  double reached = 0.0;                           // depth of the far side of its last certain layer
  std::int64_t u0 = 0, u1 = -1, v0 = 0, v1 = -1;  // its cells in the current layer
};

}  // namespace

/** What the bundles of a scan take, kept for the next. */
struct RayBundler::Buffers {
  /** A thread's band of bundles: their layer's cells and the cells they mark. A cache line of its own. */
  struct alignas(64) Band {
    std::vector<Bundle*> bundles;
    std::vector<std::uint8_t> state;
    std::vector<ScanBlock> marked;
  };

  RayBundles out;
  Face faces[6];
  EndDepths ends;
  std::vector<std::uint32_t> of;  // per ray of the face, its bundle
  std::vector<Bundle> bundles;
  std::vector<Bundle*> active;
  std::vector<Band> bands;
};

namespace {

class FaceSweep {
 public:
  FaceSweep(const CellGrid& grid, const Key& from, const float origin[3], const Face& face,
            RayBundler::Buffers& buffers)
      : res_(grid.resolution()),
        inv_res_(1.0 / grid.resolution()),
        margin_(kMargin * grid.resolution()),
        rays_(face.size()),
        face_(face),
        b_(buffers) {
    const std::int32_t key[3] = {from.x, from.y, from.z};
    for (int a = 0; a < 3; ++a) origin_[a] = origin[a], from_[a] = key[a];
  }

  /** Sweeps the face's bundles on `workers` threads, each taking a band of them. */
  void run(std::size_t workers) {
    double p0 = std::numeric_limits<double>::max(), p1 = -p0, q0 = p0, q1 = -p0;
    for (const FaceRays& part : face_.parts)
      if (!part.rays.empty()) {
        p0 = std::min(p0, part.p0), p1 = std::max(p1, part.p1);
        q0 = std::min(q0, part.q0), q1 = std::max(q1, part.q1);
      }
    // About four fine bins a ray over the rays' box, and no more than 2n bins along a side.
    const double n = double(rays_);
    const double fine = std::max({0.5 * std::sqrt((p1 - p0) * (q1 - q0) / n),
                                  std::max(p1 - p0, q1 - q0) / (2 * n), std::ldexp(1.0, -30)});
    const std::size_t nx = std::size_t((p1 - p0) / fine) + 1, ny = std::size_t((q1 - q0) / fine) + 1;
    EndDepths& ends = b_.ends;
    ends.reset(p0, q0, fine, nx, ny);
    const double wide = kBundleBins * fine;
    const std::size_t bx = std::size_t((p1 - p0) / wide) + 1, by = std::size_t((q1 - q0) / wide) + 1;
    b_.of.resize(rays_);
    b_.bundles.assign(bx * by, Bundle{});
    // Each thread reads every ray and bins those of its rows of fine bins and of bundles: no two write one.
    const std::size_t threads = std::min(workers, by);
    runWorkers(threads, [&](std::size_t w) {
      const std::size_t fine_lo = w * ny / threads, fine_hi = (w + 1) * ny / threads;
      const std::size_t wide_lo = w * by / threads, wide_hi = (w + 1) * by / threads;
      std::size_t i = 0;
      for (const FaceRays& part : face_.parts)
        for (const FaceRay& r : part.rays) {
          const std::size_t fy = std::min(std::size_t((r.q - q0) / fine), ny - 1);
          if (fy >= fine_lo && fy < fine_hi) ends.add(r.p, r.q, r.depth);
          const std::size_t y = std::min(std::size_t((r.q - q0) / wide), by - 1);
          if (y >= wide_lo && y < wide_hi) {
            const std::size_t x = std::min(std::size_t((r.p - p0) / wide), bx - 1);
            Bundle& b = b_.bundles[b_.of[i] = std::uint32_t(y * bx + x)];
            b.p0 = std::min(b.p0, r.p), b.p1 = std::max(b.p1, r.p);
            b.q0 = std::min(b.q0, r.q), b.q1 = std::max(b.q1, r.q);
            b.deepest = std::max(b.deepest, r.depth);
          }
          ++i;
        }
    });
    ends.build();

    std::vector<Bundle*>& active = b_.active;
    active.clear();
    for (Bundle& b : b_.bundles)
      if (b.p0 <= b.p1) active.push_back(&b);

    // Bands of bundles share no ray, so their threads write disjoint cuts; each marks its own cells.
    const std::size_t bands = std::max<std::size_t>(1, std::min(workers, active.size() / kBundlesPerBand));
    if (b_.bands.size() < bands) b_.bands.resize(bands);
    runWorkers(bands, [&](std::size_t w) {
      RayBundler::Buffers::Band& band = b_.bands[w];
      band.bundles.assign(active.begin() + std::ptrdiff_t(w * active.size() / bands),
                          active.begin() + std::ptrdiff_t((w + 1) * active.size() / bands));
      band.marked.clear();
      sweep(ends, band.bundles, band.state, band.marked);
    });
    for (std::size_t w = 0; w < bands; ++w)
      b_.out.blocks.insert(b_.out.blocks.end(), b_.bands[w].marked.begin(), b_.bands[w].marked.end());

    // A thread for each part's rays: they have disjoint cuts.
    runWorkers(face_.parts.size(), [&](std::size_t w) {
      std::size_t i = 0;
      for (std::size_t p = 0; p < w; ++p) i += face_.parts[p].rays.size();
      for (const FaceRay& r : face_.parts[w].rays) {
        // A ray is cut in the last layer its bundle reached and it passes whole, short of its end's.
        const double cut = std::min(b_.bundles[b_.of[i++]].reached, lastLayerBefore(r.depth));
        if (cut > 0.0) b_.out.cuts[r.ray] = (cut - margin_) / r.axis;
      }
    });
  }

 private:
  /**
   * Sweeps the layers outwards from the sensor's while a bundle is active: `state` holds the layer's
   * cells (unknown, certain or not), the certain ones go to `marked`.
   */
  void sweep(const EndDepths& ends, std::vector<Bundle*>& active, std::vector<std::uint8_t>& state,
             std::vector<ScanBlock>& marked) const {
    const unsigned a = face_.axis;
    const int sign = face_.sign;
    for (std::int64_t k = from_[a]; !active.empty(); k += sign) {
      // The layer's depths along the face's axis, from the sensor.
      const double lo = sign > 0 ? double(k) * res_ - origin_[a] : origin_[a] - double(k + 1) * res_;
      const double near = std::max(lo, 0.0), far = lo + res_;
      const double mid = 0.5 * (near + far);
      // No cell of this layer or beyond can count once a cell's tangent width is below two fine bins.
      if (far - near < 2 * margin_ || (res_ - 2 * margin_) / mid < 2 * ends.binWidth()) return;

      // Each bundle's cells here: its rays' tangent box between the layer's planes, widened by the margin.
      std::int64_t u0 = std::numeric_limits<std::int64_t>::max(),
                   u1 = std::numeric_limits<std::int64_t>::min();
      std::int64_t v0 = u0, v1 = u1;
      std::size_t kept = 0;
      for (Bundle* b : active) {
        if (b->deepest < far + margin_) continue;  // all its rays end here or before
        b->u0 = cellOf(face_.u, std::min(b->p0 * near, b->p0 * far) - margin_);
        b->u1 = cellOf(face_.u, std::max(b->p1 * near, b->p1 * far) + margin_);
        b->v0 = cellOf(face_.v, std::min(b->q0 * near, b->q0 * far) - margin_);
        b->v1 = cellOf(face_.v, std::max(b->q1 * near, b->q1 * far) + margin_);
        u0 = std::min(u0, b->u0), u1 = std::max(u1, b->u1);
        v0 = std::min(v0, b->v0), v1 = std::max(v1, b->v1);
        active[kept++] = b;
      }
      active.resize(kept);
      if (active.empty()) return;
      const std::size_t nu = std::size_t(u1 - u0 + 1), nv = std::size_t(v1 - v0 + 1);
      if (nu * nv > kLayerCellsPerRay * rays_ + 4096) return;
      state.assign(nu * nv, kUnknown);

      const double inv = 1.0 / mid;
      // A ray crossing one of these planes inside the cell passes it: the middle, then near the far and the
      // near side (the cells beside the sensor are crossed at a slant).
      const double planes[3] = {inv, 1.0 / (far - margin_), near > 0.0 ? 1.0 / (near + margin_) : 0.0};
      kept = 0;
      for (Bundle* b : active) {
        bool certain = true;
        for (std::int64_t v = b->v0; v <= b->v1 && certain; ++v)
          for (std::int64_t u = b->u0; u <= b->u1 && certain; ++u) {
            std::uint8_t& s = state[std::size_t(v - v0) * nu + std::size_t(u - u0)];
            if (s == kUnknown) {
              const double ua = double(u) * res_ - origin_[face_.u] + margin_;
              const double va = double(v) * res_ - origin_[face_.v] + margin_;
              const double ub = ua + res_ - 2 * margin_, vb = va + res_ - 2 * margin_;
              bool seen = false;
              for (const double i : planes) {
                if (i <= 0.0) continue;
                if ((seen = ends.deeper(ua * i, ub * i, va * i, vb * i, far + margin_))) break;
              }
              s = seen ? kCertain : kUncertain;
            }
            certain = s == kCertain;
          }
        if (certain) {
          b->reached = far;
          active[kept++] = b;
        }
      }
      active.resize(kept);
      mark(k, u0, v0, nu, nv, state, marked);
    }
  }

  /** The depth of the far side of the last layer that a ray ending at `depth` leaves by a margin. */
  double lastLayerBefore(double depth) const {
    const double o = origin_[face_.axis];
    if (face_.sign > 0) return double(floorOf((depth - margin_ + o) * inv_res_)) * res_ - o;
    return o + double(floorOf((depth - margin_ - o) * inv_res_)) * res_;
  }

  /** The cell of coordinate x from the sensor along `axis`; a margin's error either way is harmless. */
  std::int64_t cellOf(unsigned axis, double x) const { return floorOf((x + origin_[axis]) * inv_res_); }

  static std::int64_t floorOf(double q) {
    const std::int64_t i = std::int64_t(q);
    return i - std::int64_t(q < double(i));
  }

  /** Hands out the layer's certain cells, each a passed cell of the scan, a block's row at a time. */
  void mark(std::int64_t k, std::int64_t u0, std::int64_t v0, std::size_t nu, std::size_t nv,
            const std::vector<std::uint8_t>& state, std::vector<ScanBlock>& marked) const {
    std::int64_t key[3];
    key[face_.axis] = k;
    for (std::size_t j = 0; j < nv; ++j) {
      key[face_.v] = v0 + std::int64_t(j);
      ScanBlock run{{0, 0, 0}, 0, 0};
      for (std::size_t i = 0; i < nu; ++i) {
        if (state[j * nu + i] != kCertain) continue;
        key[face_.u] = u0 + std::int64_t(i);
        const TreeCoord c(Key{std::int32_t(key[0]), std::int32_t(key[1]), std::int32_t(key[2])});
        const std::uint32_t at[3] = {c[0] >> 2, c[1] >> 2, c[2] >> 2};
        if (run.passed != 0 && (at[0] != run.at[0] || at[1] != run.at[1] || at[2] != run.at[2])) {
          marked.push_back(run);
          run.passed = 0;
        }
        run.at[0] = at[0], run.at[1] = at[1], run.at[2] = at[2];
        run.passed |= std::uint64_t(1) << ((c[0] & 3u) + 4 * (c[1] & 3u) + 16 * (c[2] & 3u));
      }
      if (run.passed != 0) marked.push_back(run);
    }
  }

  static constexpr std::uint8_t kUnknown = 0, kCertain = 1, kUncertain = 2;
  double res_, inv_res_, margin_;
  std::size_t rays_;
  double origin_[3];
  std::int64_t from_[3];
  const Face& face_;
  RayBundler::Buffers& b_;
};

}  // namespace

RayBundler::RayBundler() : buffers_(std::make_unique<Buffers>()) {}
RayBundler::~RayBundler() = default;

const RayBundles& RayBundler::bundle(const CellGrid& grid, const float sensor[3], const float* ends,
                                     std::size_t count, std::size_t workers) {
  Buffers& b = *buffers_;
  RayBundles& out = b.out;
  out.cuts.clear();
  out.blocks.clear();
  Key from;
  if (count == 0 || count > std::numeric_limits<std::uint32_t>::max() ||
      !grid.pointToKey(sensor[0], sensor[1], sensor[2], from))
    return out;
  // Which faces are worth sweeping, judged on a sample of the rays.
  FaceSample sample[6];
  for (std::size_t i = 0; i < count; i += kSampleEvery) {
    double d[3];
    for (int a = 0; a < 3; ++a) d[a] = double(ends[3 * i + a]) - sensor[a];
    const unsigned a = faceAxis(d);
    if (d[a] != 0.0) sample[2 * a + (d[a] < 0 ? 1 : 0)].add(d, a);
  }
  bool any = false;
  for (FaceSample& f : sample)
    any |= (f.worth = f.raysAcrossACell(grid.resolution(), kSampleEvery) >= kMinRaysAcross);
  if (!any) return out;

  out.cuts.assign(count, 0.0);
  for (unsigned f = 0; f < 6; ++f) {
    Face& face = b.faces[f];
    face.axis = f / 2, face.u = (f / 2 + 1) % 3, face.v = (f / 2 + 2) % 3, face.sign = f % 2 ? -1 : 1;
    face.parts.resize(workers);
  }
  // The sensor relative to the grid, as setupRay gives it for every ray.
  float origin[3];
  for (int a = 0; a < 3; ++a) origin[a] = float(double(sensor[a]) - grid.origin()[a]);
  runWorkers(workers, [&](std::size_t w) {
    // Each thread fills a vector of its own: the faces' parts lie side by side, in one cache line.
    FaceRays mine[6];
    for (unsigned f = 0; f < 6; ++f) {
      mine[f].rays.swap(b.faces[f].parts[w].rays);
      mine[f].rays.clear();
      mine[f].p0 = mine[f].q0 = std::numeric_limits<double>::max();
      mine[f].p1 = mine[f].q1 = -std::numeric_limits<double>::max();
    }
    for (std::size_t i = w * count / workers, last = (w + 1) * count / workers; i < last; ++i) {
      const float* end = ends + 3 * i;
      // A ray ending in the sensor's cell is not walked; it ends in the first layer, so it neither has a
      // cut nor counts for a cell.
      const RaySetup ray = setupRay(grid, sensor, end);
      if (!(ray.length > 0.0f)) continue;
      const double d[3] = {ray.direction[0], ray.direction[1], ray.direction[2]};
      const unsigned a = faceAxis(d);
      const double along = std::fabs(d[a]);
      const unsigned f = 2 * a + (d[a] < 0 ? 1 : 0);
      if (!(along > 0.0) || !sample[f].worth) continue;
      // The walk stops at the end's cell or at the ray's length, whichever its float ray reaches first.
      const double sign = d[a] < 0 ? -1.0 : 1.0;
      const double depth = std::min(along * double(ray.length),
                                    sign * (double(end[a]) - grid.origin()[a] - double(ray.origin[a])));
      const Face& face = b.faces[f];
      FaceRays& to = mine[f];
      const double p = d[face.u] / along, q = d[face.v] / along;
      to.rays.push_back(FaceRay{p, q, depth, along, std::uint32_t(i)});
      to.p0 = std::min(to.p0, p), to.p1 = std::max(to.p1, p);
      to.q0 = std::min(to.q0, q), to.q1 = std::max(to.q1, q);
    }
    for (unsigned f = 0; f < 6; ++f) std::swap(mine[f], b.faces[f].parts[w]);
  });
  for (const Face& face : b.faces)
    if (face.size() != 0) FaceSweep(grid, from, origin, face, b).run(workers);
  return out;
}

}  // namespace detail
}  // namespace fot
}  // namespace pcl
