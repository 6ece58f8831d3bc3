// Rigid-body quadrotor dynamics (world ENU, body FLU), integrated with RK4.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>

#include "go_feap/common/result.h"

namespace go_feap::sim {

/// Physical parameters of an X-configuration quadrotor (defaults: ~1 kg class vehicle).
struct QuadrotorParams {
  double mass = 0.98;                                    ///< kg
  Eigen::Vector3d inertia{2.64e-3, 2.64e-3, 4.96e-3};    ///< kg m^2, diagonal of J (body axes)
  double arm_length = 0.17;                              ///< m, rotor centre to body centre
  double torque_coefficient = 0.016;                     ///< m, yaw torque per newton of rotor thrust
  double motor_min_thrust = 0.0;                         ///< N per motor
  double motor_max_thrust = 4.5;                         ///< N per motor
  double linear_drag = 0.0;                              ///< N s/m, optional drag force -c v
  double gravity = 9.81;                                 ///< m/s^2
  double dynamics_rate = 500.0;                          ///< Hz, RK4 step rate (>= 500)

  common::Status validate() const;
};

/// Rigid-body state.
struct QuadrotorState {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();          ///< m, world
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();          ///< m/s, world
  Eigen::Quaterniond attitude = Eigen::Quaterniond::Identity();  ///< body -> world
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  ///< rad/s, body
  /// Heading (rad, in (-pi, pi]): the body x axis's direction about world z.
  double heading() const {
    const Eigen::Matrix3d R = attitude.toRotationMatrix();
    return std::atan2(R(1, 0), R(0, 0));
  }
  /// False once the dynamics diverged (a stiff configuration: gains too high for the inertia at
  /// dynamics_rate); nothing should be measured or published from such a state.
  bool finite() const {
    return position.allFinite() && velocity.allFinite() && attitude.coeffs().allFinite() &&
           angular_velocity.allFinite();
  }
};

/// Collective thrust and body moments asked of the vehicle.
struct Wrench {
  double thrust = 0.0;                               ///< N along body +z
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();  ///< N m, body
};

class Quadrotor {
 public:
  explicit Quadrotor(const QuadrotorParams& params);

  const QuadrotorParams& params() const { return params_; }
  const QuadrotorState& state() const { return state_; }
  void setState(const QuadrotorState& state) { state_ = state; }

  /// Maps a wanted wrench to the four rotor thrusts and returns the wrench the rotors really produce:
  /// the wanted one when every rotor is within the motor limits, else one that keeps the roll and pitch
  /// moments (scaled down in proportion only when the rotors cannot span them), then as much of the
  /// collective thrust, then of the yaw moment, as the limits leave.
  Wrench saturate(const Wrench& wanted) const;
  /// Rotor thrusts (N) for a wrench, before clamping (front-left, front-right, rear-right, rear-left).
  Eigen::Vector4d rotorThrusts(const Wrench& w) const;

  /// Advances by one RK4 step of length dt with the wrench held constant (the wrench is
  /// saturated first). Returns the applied wrench.
  Wrench step(const Wrench& wanted, double dt);

 private:
  struct Derivative;
  Derivative derivative(const QuadrotorState& s, const Wrench& w) const;

  QuadrotorParams params_;
  Eigen::Matrix4d allocation_;      ///< [thrust; Mx; My; Mz] = allocation_ * rotor thrusts
  Eigen::Matrix4d allocation_inv_;
  QuadrotorState state_;
};

}  // namespace go_feap::sim
