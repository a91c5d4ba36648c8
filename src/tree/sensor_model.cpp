#include <pcl_fot/tree/sensor_model.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace pcl {
namespace fot {

float SensorModel::logOdds(double probability) {
  return float(std::log(probability / (1.0 - probability)));
}

double SensorModel::probability(double log_odds) {
  return 1.0 - 1.0 / (1.0 + std::exp(log_odds));
}

SensorModel::SensorModel(double prob_hit, double prob_miss, double clamp_min, double clamp_max,
                         double occupancy)
    : prob_hit_(prob_hit),
      prob_miss_(prob_miss),
      clamp_min_(clamp_min),
      clamp_max_(clamp_max),
      occupancy_(occupancy) {
  const struct {
    const char* name;
    double p;
  } all[] = {{"prob_hit", prob_hit},
             {"prob_miss", prob_miss},
             {"clamp_min", clamp_min},
             {"clamp_max", clamp_max},
             {"occupancy", occupancy}};
  for (const auto& a : all)
    if (!(a.p > 0.0 && a.p < 1.0))
      throw std::invalid_argument(std::string("pcl::fot::SensorModel: ") + a.name + " = " +
                                  std::to_string(a.p) + " is not a probability in (0, 1)");
  hit_ = logOdds(prob_hit);
  miss_ = logOdds(prob_miss);
  min_ = logOdds(clamp_min);
  max_ = logOdds(clamp_max);
  thres_ = logOdds(occupancy);
  if (!(hit_ > 0.0f)) throw std::invalid_argument("pcl::fot::SensorModel: prob_hit must exceed 0.5");
  if (!(miss_ < 0.0f)) throw std::invalid_argument("pcl::fot::SensorModel: prob_miss must be below 0.5");
  if (!(min_ < thres_ && thres_ <= max_))
    throw std::invalid_argument(
        "pcl::fot::SensorModel: the clamps must enclose the threshold, clamp_min < occupancy <= clamp_max");
}

}  // namespace fot
}  // namespace pcl
