#include "go_feap/sim/quadrotor.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace go_feap::sim {

common::Status QuadrotorParams::validate() const {
  auto bad = [](const std::string& key, const std::string& why) {
    return common::Status::Error("quadrotor: " + key + " " + why);
  };
  // Every value finite: an infinite arm length or torque coefficient made the rotor allocation singular,
  // and an infinite drag the state NaN at the first step.
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(mass)) return bad("mass", "must be finite and > 0");
  if (!(inertia.array() > 0.0).all() || !inertia.allFinite()) return bad("inertia", "must be three values > 0");
  if (!positive(arm_length)) return bad("arm_length", "must be finite and > 0");
  if (!positive(torque_coefficient)) return bad("torque_coefficient", "must be finite and > 0");
  if (!positive(gravity)) return bad("gravity", "must be finite and > 0");
  if (!(motor_min_thrust >= 0.0 && std::isfinite(motor_min_thrust))) return bad("motor_min_thrust", "must be finite and >= 0");
  if (!(motor_max_thrust > motor_min_thrust && std::isfinite(motor_max_thrust)))
    return bad("motor_max_thrust", "must be finite and > motor_min_thrust");
  if (!(4.0 * motor_max_thrust > mass * gravity)) return bad("motor_max_thrust", "cannot lift the vehicle (4 x max < m g)");
  // At 4 x min >= m g the vehicle cannot hover or descend: it climbs for good.
  if (!(4.0 * motor_min_thrust < mass * gravity)) return bad("motor_min_thrust", "leaves no hover (4 x min >= m g)");
  // Bounded above too: at 1e15 Hz one simulated step never ended, and the bench could not be stopped.
  if (!(dynamics_rate >= 500.0 && dynamics_rate <= 100000.0)) return bad("dynamics_rate", "must be in [500, 100000] Hz");
  // The drag's decay rate linear_drag / mass within one step's worth of dynamics_rate: RK4 diverges past
  // about 2.8 steps' worth (5000 N s/m on 0.98 kg at 500 Hz made the state NaN).
  if (!(linear_drag >= 0.0 && linear_drag <= mass * dynamics_rate))
    return bad("linear_drag", "must be >= 0 and <= mass x dynamics_rate (the RK4 step would diverge)");
  return common::Status::Ok();
}

Quadrotor::Quadrotor(const QuadrotorParams& params) : params_(params) {
  // X configuration, rotors at 45 deg: FL (+x+y, CCW), FR (+x-y, CW), RR (-x-y, CCW), RL (-x+y, CW).
  const double d = params.arm_length / std::sqrt(2.0), k = params.torque_coefficient;
  allocation_ << 1, 1, 1, 1,     //
      d, -d, -d, d,              // roll moment: +y rotors push up
      -d, -d, d, d,              // pitch moment: -x rotors push up
      -k, k, -k, k;              // CCW rotors react CW
  allocation_inv_ = allocation_.inverse();
}

Eigen::Vector4d Quadrotor::rotorThrusts(const Wrench& w) const {
  Eigen::Vector4d u;
  u << w.thrust, w.moment;
  return allocation_inv_ * u;
}

Wrench Quadrotor::saturate(const Wrench& wanted) const {
  const double lo = params_.motor_min_thrust, hi = params_.motor_max_thrust;
  const Eigen::Vector4d exact = rotorThrusts(wanted);
  if ((exact.array() >= lo).all() && (exact.array() <= hi).all()) {
    const Eigen::Vector4d u = allocation_ * exact;
    return {u[0], u.tail<3>()};
  }
  // Past the motor limits the rotors give up the yaw moment first, then collective thrust, and keep the
  // roll and pitch moments, which are what turn the vehicle back upright. Clamping each rotor on its own
  // (as before) let a large collective demand, all four rotors at their maximum, leave no moment at all:
  // after a reference step of many metres down the vehicle pitched on past the tilt limit and fell.
  const Eigen::Vector4d roll_pitch = allocation_inv_ * Eigen::Vector4d(0.0, wanted.moment.x(), wanted.moment.y(), 0.0);
  const Eigen::Vector4d yaw = allocation_inv_ * Eigen::Vector4d(0.0, 0.0, 0.0, wanted.moment.z());
  Eigen::Vector4d rp = roll_pitch;
  if (!rp.allFinite() || !yaw.allFinite() || !std::isfinite(wanted.thrust)) {
    const Eigen::Vector4d f = exact.cwiseMax(lo).cwiseMin(hi);  // no order among NaNs: clamp and go
    const Eigen::Vector4d u = allocation_ * (f.allFinite() ? f : Eigen::Vector4d::Constant(lo));
    return {u[0], u.tail<3>()};
  }
  const double spread = rp.maxCoeff() - rp.minCoeff();
  if (spread > hi - lo) rp *= (hi - lo) / spread;  // more roll/pitch than the rotors span: keep its direction
  // The collective per rotor nearest the wanted one that leaves room for the roll/pitch part.
  const double collective = std::max(std::min(0.25 * wanted.thrust, hi - rp.maxCoeff()), lo - rp.minCoeff());
  double yaw_share = 1.0;  // the largest share of the yaw part that still fits every rotor
  for (int i = 0; i < 4; ++i) {
    const double base = collective + rp[i];
    if (yaw[i] > 0.0) yaw_share = std::min(yaw_share, (hi - base) / yaw[i]);
    if (yaw[i] < 0.0) yaw_share = std::min(yaw_share, (lo - base) / yaw[i]);
  }
  yaw_share = std::max(yaw_share, 0.0);
  const Eigen::Vector4d f =
      (Eigen::Vector4d::Constant(collective) + rp + yaw_share * yaw).cwiseMax(lo).cwiseMin(hi);  // round-off
  const Eigen::Vector4d u = allocation_ * f;
  return {u[0], u.tail<3>()};
}

struct Quadrotor::Derivative {
  Eigen::Vector3d dp, dv;
  Eigen::Vector4d dq;  // quaternion derivative (w, x, y, z)
  Eigen::Vector3d dw;
};

Quadrotor::Derivative Quadrotor::derivative(const QuadrotorState& s, const Wrench& w) const {
  Derivative d;
  const Eigen::Matrix3d R = s.attitude.normalized().toRotationMatrix();
  d.dp = s.velocity;
  d.dv = (w.thrust * R.col(2) - params_.linear_drag * s.velocity) / params_.mass -
         Eigen::Vector3d(0, 0, params_.gravity);
  // q_dot = 0.5 q ⊗ (0, w_body)
  const Eigen::Quaterniond omega(0.0, s.angular_velocity.x(), s.angular_velocity.y(), s.angular_velocity.z());
  const Eigen::Quaterniond qd = s.attitude * omega;
  d.dq << 0.5 * qd.w(), 0.5 * qd.x(), 0.5 * qd.y(), 0.5 * qd.z();
  const Eigen::Vector3d Jw = params_.inertia.cwiseProduct(s.angular_velocity);
  d.dw = (w.moment - s.angular_velocity.cross(Jw)).cwiseQuotient(params_.inertia);
  return d;
}

Wrench Quadrotor::step(const Wrench& wanted, double dt) {
  // NaN or infinite made the state NaN, a negative step integrated backwards.
  if (!(dt > 0.0 && std::isfinite(dt))) throw std::invalid_argument("Quadrotor::step: dt must be finite and > 0");
  const Wrench w = saturate(wanted);
  auto advance = [](const QuadrotorState& s, const Derivative& d, double h) {
    QuadrotorState n = s;
    n.position += h * d.dp;
    n.velocity += h * d.dv;
    n.attitude.coeffs() += h * Eigen::Vector4d(d.dq[1], d.dq[2], d.dq[3], d.dq[0]);  // coeffs: x y z w
    n.angular_velocity += h * d.dw;
    return n;
  };
  const Derivative k1 = derivative(state_, w);
  const Derivative k2 = derivative(advance(state_, k1, 0.5 * dt), w);
  const Derivative k3 = derivative(advance(state_, k2, 0.5 * dt), w);
  const Derivative k4 = derivative(advance(state_, k3, dt), w);
  Derivative sum;
  sum.dp = (k1.dp + 2 * k2.dp + 2 * k3.dp + k4.dp) / 6.0;
  sum.dv = (k1.dv + 2 * k2.dv + 2 * k3.dv + k4.dv) / 6.0;
  sum.dq = (k1.dq + 2 * k2.dq + 2 * k3.dq + k4.dq) / 6.0;
  sum.dw = (k1.dw + 2 * k2.dw + 2 * k3.dw + k4.dw) / 6.0;
  state_ = advance(state_, sum, dt);
  state_.attitude.normalize();
  return w;
}

}  // namespace go_feap::sim
