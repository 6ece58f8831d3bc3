// Dynamics and controller stepped together in simulated time.
#pragma once

#include "go_feap/sim/quadrotor.h"
#include "go_feap/sim/so3_controller.h"

namespace go_feap::sim {

/// A quadrotor flown by the geometric controller; the controller runs at every dynamics
/// step. Time is simulated seconds; nothing here reads a clock.
class SimulatedVehicle {
 public:
  SimulatedVehicle(const QuadrotorParams& params, const So3ControllerConfig& control);

  /// Places the vehicle at rest, level, at `position` with heading `yaw`.
  void reset(const Eigen::Vector3d& position, double yaw, double time = 0.0);

  /// Sets the full state (e.g. to start already moving).
  void setState(const QuadrotorState& state) { quad_.setState(state); }

  /// Advances by `duration` seconds towards `ref` (held constant) in steps of
  /// 1 / dynamics_rate (the last step may be shorter).
  void advance(double duration, const PositionReference& ref);

  const QuadrotorState& state() const { return quad_.state(); }
  const Quadrotor& quadrotor() const { return quad_; }
  double time() const { return time_; }
  /// Rotor thrusts (N) actually applied in the last step.
  const Eigen::Vector4d& lastRotorThrusts() const { return last_rotors_; }
  /// Rotor thrusts (N) the controller asked for in the last step, before clamping.
  const Eigen::Vector4d& lastWantedRotorThrusts() const { return last_wanted_rotors_; }

 private:
  Quadrotor quad_;
  So3Controller controller_;
  double time_ = 0.0;
  Eigen::Vector4d last_rotors_ = Eigen::Vector4d::Zero();
  Eigen::Vector4d last_wanted_rotors_ = Eigen::Vector4d::Zero();
};

}  // namespace go_feap::sim
