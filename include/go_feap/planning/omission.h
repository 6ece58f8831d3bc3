// Omission likelihood of a frontier (DESIGN §3.5, paper eqs. 5-7): how likely the UAV is to
// leave the frontier behind, expressed in seconds of equivalent flight time.
#pragma once

#include "go_feap/common/result.h"

namespace go_feap::planning {

/// Constants of xi = alpha(|C|) * omega(T) * beta(N_near).
///
/// alpha is dimensionless and decreases with the frontier's size: small frontiers are the
/// ones a UAV passes by and leaves behind, large ones keep attracting it anyway.
///   alpha(c) = alpha_max                    for c <= c_small
///   alpha(c) = alpha_max * c_small / c      for c >  c_small
/// omega (seconds) favours frontiers that appeared recently, i.e. around where the UAV is
/// working now:      omega(T) = w_t  if T < t_max, else 0.
/// beta (dimensionless) favours frontiers in a small group: a lone frontier (N = 0) or one
/// inside a large field of frontiers (N >= n_max) is not singled out:
///                   beta(N)  = n_t  if 0 < N < n_max, else 0.
struct OmissionConfig {
  double alpha_max = 1.0;  ///< alpha of a frontier with at most c_small cells
  int c_small = 30;        ///< cells; larger frontiers get alpha_max * c_small / |C|
  double w_t = 2.0;        ///< s, omega of a frontier younger than t_max
  double t_max = 20.0;     ///< s, frontiers at least this old get omega = 0
  double n_t = 1.0;        ///< beta of a frontier with 0 < N_near < n_max
  int n_max = 5;           ///< frontiers with N_near >= n_max get beta = 0

  /// Checks every key; the message names the bad one, e.g. "omission: t_max must be > 0".
  common::Status validate() const;
};

/// Size factor for a frontier of `cell_count` cells (negative counts read as 0).
double alpha(const OmissionConfig& config, int cell_count);
/// Duration factor (s) for a frontier that has existed for `duration` seconds.
double omega(const OmissionConfig& config, double duration);
/// Neighbourhood factor for a frontier with `n_near` other frontiers within S_near.
double beta(const OmissionConfig& config, int n_near);
/// Omission likelihood xi = alpha * omega * beta, in seconds of equivalent flight time (>= 0).
double xi(const OmissionConfig& config, int cell_count, double duration, int n_near);

}  // namespace go_feap::planning
