// Geometric tracking controller on SE(3) (Lee, Leok, McClamroch, CDC 2010).
#pragma once

#include <Eigen/Core>

#include "go_feap/common/grid.h"
#include "go_feap/sim/quadrotor.h"

namespace go_feap::sim {

/// Full-state reference, as carried by go_feap/PositionCommand (world frame).
struct PositionReference {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();      ///< m
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();      ///< m/s
  Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();  ///< m/s^2, feed-forward
  double yaw = 0.0;                                        ///< rad
  double yaw_dot = 0.0;                                    ///< rad/s
};

struct So3ControllerConfig {
  Eigen::Vector3d kx{8.8, 8.8, 10.0};     ///< N/m, position gains
  Eigen::Vector3d kv{5.3, 5.3, 6.0};      ///< N s/m, velocity gains
  Eigen::Vector3d kR{1.05, 1.05, 0.45};   ///< N m/rad, attitude gains
  Eigen::Vector3d kw{0.095, 0.095, 0.07}; ///< N m s/rad, angular-rate gains
  double max_tilt = 0.61;                 ///< rad, largest angle between thrust and vertical

  common::Status validate() const;
};

class So3Controller {
 public:
  So3Controller(const So3ControllerConfig& config, const QuadrotorParams& vehicle);
  /// Thrust and moments that drive `state` towards `ref`.
  Wrench compute(const QuadrotorState& state, const PositionReference& ref) const;

 private:
  So3ControllerConfig config_;
  QuadrotorParams vehicle_;
};

/// Why a reference is refused: NaN/Inf, |acceleration| > max_acceleration, |velocity| > max_speed,
/// |yaw_dot| > max_yaw_rate, or position more than `max_outside` metres outside `bounds`. Ok when usable.
common::Status checkReference(const PositionReference& ref, const common::Aabb& bounds,
                              double max_acceleration = 50.0, double max_outside = 10.0, double max_speed = 20.0,
                              double max_yaw_rate = 20.0);

}  // namespace go_feap::sim
