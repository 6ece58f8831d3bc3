#include "go_feap/planning/omission.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace go_feap::planning {

using common::Status;

Status OmissionConfig::validate() const {
  auto err = [](const char* key, const char* why) {
    return Status::Error(std::string("omission: ") + key + " " + why);
  };
  if (!(alpha_max >= 0.0 && std::isfinite(alpha_max))) return err("alpha_max", "must be >= 0");
  if (c_small <= 0) return err("c_small", "must be > 0");
  if (!(w_t >= 0.0 && std::isfinite(w_t))) return err("w_t", "must be >= 0");
  if (!(t_max > 0.0 && std::isfinite(t_max))) return err("t_max", "must be > 0");
  if (!(n_t >= 0.0 && std::isfinite(n_t))) return err("n_t", "must be >= 0");
  if (n_max <= 1) return err("n_max", "must be > 1");
  return Status::Ok();
}

double alpha(const OmissionConfig& config, int cell_count) {
  const int c = std::max(cell_count, 0);
  if (c <= config.c_small) return config.alpha_max;
  return config.alpha_max * static_cast<double>(config.c_small) / static_cast<double>(c);
}

double omega(const OmissionConfig& config, double duration) {
  return duration < config.t_max ? config.w_t : 0.0;
}

double beta(const OmissionConfig& config, int n_near) {
  return (n_near > 0 && n_near < config.n_max) ? config.n_t : 0.0;
}

double xi(const OmissionConfig& config, int cell_count, double duration, int n_near) {
  return alpha(config, cell_count) * omega(config, duration) * beta(config, n_near);
}

}  // namespace go_feap::planning
