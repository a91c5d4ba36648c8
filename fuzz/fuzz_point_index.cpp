// Fuzz target: PointIndex, the exact search behind FastOctTreeSearch, against brute force. The input picks
// a resolution (or none, for the cell edge picked from the points), k, a metric and a radius, then points:
// raw floats (NaN, Inf, huge, denormal), multiples of 1/64 (ties, duplicates, points on cell faces) or
// multiples of 10^6. Every point is a query; k-NN and radius results must equal brute force's, distances to
// the bit, ties to the smaller index. Then, if the input asks, a third of the points are removed and added
// again, every other one under its old index (as FastOctTreeSearch gives removed points' indices to new
// ones) and the rest under new indices, and every query is asked again.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include <pcl_fot/search/point_index.h>

namespace {

using pcl::fot::Metric;

/** PCL's distances: FLANN sums the axes left to right in float. */
float distance(Metric metric, const float* p, const float* q) {
  const float dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
  return metric == Metric::Euclidean ? dx * dx + dy * dy + dz * dz
                                     : std::fabs(dx) + std::fabs(dy) + std::fabs(dz);
}

bool finite3(const float* p) {
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

struct Hit {
  float d;
  std::int32_t i;
  bool operator<(const Hit& o) const { return d < o.d || (d == o.d && i < o.i); }
};

void expectSame(const std::vector<Hit>& want, std::size_t got, const std::vector<std::int32_t>& ids,
                const std::vector<float>& ds) {
  if (got != want.size() || ids.size() != got || ds.size() != got) std::abort();
  for (std::size_t j = 0; j < got; ++j)
    if (ds[j] != want[j].d || ids[j] != want[j].i) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const double kResolutions[] = {0.01, 0.05, 0.1, 1.0, 0.003, 7.5, 1e-6, 1e3};
  static const double kRadii[] = {0, 1e-3, 0.05, 0.5, 3, 1e6, 1e30, 0.0123};
  if (size < 5) return 0;
  const double resolution = kResolutions[data[0] % 8];
  const bool automatic = data[0] & 8;  // an index that picks its own cell edge
  const std::size_t k = 1 + data[1] % 20;
  const Metric metric = data[2] & 1 ? Metric::Manhattan : Metric::Euclidean;
  const bool updates = data[2] & 2;         // remove a third of the points and add them back
  const std::size_t dropped = data[1] % 3;  // which third
  const double radius = kRadii[data[3] % 8];
  const int mode = data[4] % 3;
  data += 5, size -= 5;

  std::vector<float> xyz;
  const std::size_t bytes = mode == 0 ? 4 : 2;
  for (std::size_t at = 0; at + bytes <= size && xyz.size() < 3 * 300; at += bytes) {
    float v;
    if (mode == 0) {
      std::memcpy(&v, data + at, 4);
    } else {
      std::int16_t s;
      std::memcpy(&s, data + at, 2);
      v = mode == 1 ? float(s) / 64.0f : float(s) * 1e6f;
    }
    xyz.push_back(v);
  }
  const std::size_t n = xyz.size() / 3;
  if (n < 2) return 0;
  const std::size_t points = n - 1;  // the last triple is only a query

  pcl::fot::PointIndex index = automatic ? pcl::fot::PointIndex() : pcl::fot::PointIndex(resolution);
  index.build(xyz.data(), points, 3 * sizeof(float));
  if (!(index.resolution() > 0.0 && std::isfinite(index.resolution()))) std::abort();
  // The points held: their coordinates and indices.
  std::vector<std::pair<const float*, std::int32_t>> held;
  for (std::size_t i = 0; i < points; ++i)
    if (finite3(&xyz[3 * i])) held.emplace_back(&xyz[3 * i], std::int32_t(i));
  std::vector<std::int32_t> ids;
  std::vector<float> ds;
  std::vector<Hit> all;
  const auto check = [&] {
    if (index.size() != held.size()) std::abort();
    for (std::size_t qi = 0; qi < n; ++qi) {
      const float* q = &xyz[3 * qi];
      if (!finite3(q)) {
        if (index.nearestK(q, k, metric, ids, ds) != 0) std::abort();
        continue;
      }
      all.clear();
      for (const auto& [p, i] : held) all.push_back(Hit{distance(metric, p, q), i});
      std::sort(all.begin(), all.end());

      const std::vector<Hit> nearest(all.begin(), all.begin() + std::ptrdiff_t(std::min(k, all.size())));
      expectSame(nearest, index.nearestK(q, k, metric, ids, ds), ids, ds);

      const double limit = metric == Metric::Euclidean ? radius * radius : radius;
      std::size_t inside = 0;
      while (inside < all.size() && double(all[inside].d) <= limit) ++inside;
      const std::vector<Hit> within(all.begin(), all.begin() + std::ptrdiff_t(inside));
      expectSame(within, index.radiusSearch(q, radius, metric, ids, ds), ids, ds);
    }
  };
  check();
  if (!updates) return 0;
  // Updates in place: every third point held goes, then comes back, as point `points + j` or under the index
  // it had (the indices then come in no order).
  std::vector<std::int32_t> gone;
  std::vector<float> back;
  std::vector<std::pair<const float*, std::int32_t>> kept;
  for (std::size_t j = 0; j < held.size(); ++j) {
    if (j % 3 == dropped) {
      gone.push_back(held[j].second);
      back.insert(back.end(), held[j].first, held[j].first + 3);
    } else {
      kept.push_back(held[j]);
    }
  }
  if (index.remove(gone.data(), gone.size()) != gone.size()) std::abort();
  held = kept;
  check();
  std::vector<std::int32_t> again(gone.size());
  for (std::size_t j = 0; j < gone.size(); ++j) again[j] = j % 2 ? std::int32_t(points + j) : gone[j];
  if (index.add(back.data(), gone.size(), 3 * sizeof(float), again.data()) != gone.size()) std::abort();
  for (std::size_t j = 0; j < gone.size(); ++j) held.emplace_back(&back[3 * j], again[j]);
  check();
  return 0;
}
