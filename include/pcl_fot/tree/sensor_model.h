#pragma once

#include <cstdint>

namespace pcl {
namespace fot {

/**
 * How a map fuses its scans. Binary is the paper's rule: a write sets a cell, and the latest scan wins.
 * LogOdds is OctoMap's: each scan adds a hit or a miss to a cell's clamped log-odds (see SensorModel).
 */
enum class UpdateRule : std::uint8_t { Binary = 0, LogOdds = 1 };

/**
 * OctoMap's sensor model, with OctoMap's defaults and arithmetic: the probabilities are stored as float
 * log-odds, (float) log(p / (1 - p)) of the double p, so that updates give OctoMap's floats bit for bit.
 *
 * A cell at a clamp is settled: free at the lower clamp, occupied at the upper one. The tree stores
 * settled cells as bare states; only cells between the clamps carry a value. A cell is occupied when its
 * log-odds is at least the threshold's.
 */
class SensorModel {
 public:
  /**
   * Throws std::invalid_argument unless every probability lies in (0, 1), a hit raises the log-odds and a
   * miss lowers it (hit above 0.5, miss below), and clamp_min < occupancy <= clamp_max as log-odds.
   */
  explicit SensorModel(double prob_hit, double prob_miss = 0.4, double clamp_min = 0.1192,
                       double clamp_max = 0.971, double occupancy = 0.5);
  /** OctoMap's defaults. Not explicit, so that options holding a model can be written `= {}`. */
  SensorModel() : SensorModel(0.7) {}

  double probHit() const { return prob_hit_; }
  double probMiss() const { return prob_miss_; }
  double clampMin() const { return clamp_min_; }
  double clampMax() const { return clamp_max_; }
  double occupancy() const { return occupancy_; }

  float hitLogOdds() const { return hit_; }
  float missLogOdds() const { return miss_; }
  float clampMinLogOdds() const { return min_; }
  float clampMaxLogOdds() const { return max_; }
  float occupancyLogOdds() const { return thres_; }

  /** OctoMap's updateNodeLogOdds: the value plus the update, clamped. */
  float update(float value, float update) const {
    value += update;
    if (value < min_) return min_;
    return value > max_ ? max_ : value;
  }
  /** OctoMap's updateNode's early exit: an update towards a clamp the value has reached changes nothing. */
  bool pinned(float value, float update) const {
    return (update >= 0.0f && value >= max_) || (update <= 0.0f && value <= min_);
  }
  /**
   * OctoMap's updateNode on one cell: the value (NaN for an unknown cell, which starts at 0) plus the
   * update, clamped. Returns false, and leaves the value, when it has reached the clamp the update heads for.
   */
  bool updateNode(float& value, float update) const {
    const bool known = value == value;
    if (known && pinned(value, update)) return false;
    value = this->update(known ? value : 0.0f, update);
    return true;
  }
  bool occupied(float log_odds) const { return log_odds >= thres_; }
  bool settled(float log_odds) const { return log_odds == min_ || log_odds == max_; }

  /** OctoMap's logodds() and probability(). */
  static float logOdds(double probability);
  static double probability(double log_odds);

  /** Same parameters. */
  friend bool operator==(const SensorModel& a, const SensorModel& b) {
    return a.prob_hit_ == b.prob_hit_ && a.prob_miss_ == b.prob_miss_ && a.clamp_min_ == b.clamp_min_ &&
           a.clamp_max_ == b.clamp_max_ && a.occupancy_ == b.occupancy_;
  }
  friend bool operator!=(const SensorModel& a, const SensorModel& b) { return !(a == b); }

 private:
  double prob_hit_, prob_miss_, clamp_min_, clamp_max_, occupancy_;
  float hit_, miss_, min_, max_, thres_;
};

}  // namespace fot
}  // namespace pcl
