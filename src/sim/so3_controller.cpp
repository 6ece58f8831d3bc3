#include "go_feap/sim/so3_controller.h"

#include <cmath>
#include <sstream>

namespace go_feap::sim {

namespace {

Eigen::Vector3d vee(const Eigen::Matrix3d& m) { return Eigen::Vector3d(m(2, 1), m(0, 2), m(1, 0)); }

}  // namespace

common::Status So3ControllerConfig::validate() const {
  auto positive = [](const Eigen::Vector3d& v) { return v.allFinite() && (v.array() > 0.0).all(); };
  if (!positive(kx)) return common::Status::Error("controller: kx must be three gains > 0");
  if (!positive(kv)) return common::Status::Error("controller: kv must be three gains > 0");
  if (!positive(kR)) return common::Status::Error("controller: kR must be three gains > 0");
  if (!positive(kw)) return common::Status::Error("controller: kw must be three gains > 0");
  if (!(max_tilt > 0.05 && max_tilt < 1.4)) return common::Status::Error("controller: max_tilt must be in (0.05, 1.4) rad");
  return common::Status::Ok();
}

So3Controller::So3Controller(const So3ControllerConfig& config, const QuadrotorParams& vehicle)
    : config_(config), vehicle_(vehicle) {}

Wrench So3Controller::compute(const QuadrotorState& s, const PositionReference& ref) const {
  const double m = vehicle_.mass, g = vehicle_.gravity;
  const Eigen::Matrix3d R = s.attitude.toRotationMatrix();
  const Eigen::Vector3d ep = s.position - ref.position, ev = s.velocity - ref.velocity;
  Eigen::Vector3d F = -config_.kx.cwiseProduct(ep) - config_.kv.cwiseProduct(ev) +
                      m * (ref.acceleration + Eigen::Vector3d(0, 0, g)) + vehicle_.linear_drag * ref.velocity;
  // Tilt limit: keep the vertical component, shorten the horizontal one.
  F.z() = std::max(F.z(), 0.2 * m * g);
  const double horizontal = F.head<2>().norm(), limit = F.z() * std::tan(config_.max_tilt);
  if (horizontal > limit) F.head<2>() *= limit / horizontal;

  const Eigen::Vector3d b3 = F.normalized();
  // The heading aimed at is at most a quarter turn from the present one: the attitude error's size is the
  // sine of the angle, so a heading reference half a turn round (an error of pi) gave no yaw moment at all
  // and the vehicle never turned; nearer pi it turned slowly. Within a quarter turn this is the reference.
  const double yaw_now = s.heading();
  const double yaw_error = std::remainder(ref.yaw - yaw_now, 2.0 * M_PI);
  const double yaw_aim = std::abs(yaw_error) > 0.5 * M_PI ? yaw_now + std::copysign(0.5 * M_PI, yaw_error) : ref.yaw;
  const Eigen::Vector3d b1c(std::cos(yaw_aim), std::sin(yaw_aim), 0.0);
  Eigen::Vector3d b2 = b3.cross(b1c);
  if (b2.norm() < 1e-6) b2 = R.col(1);  // heading undefined when b1c is parallel to b3
  b2.normalize();
  Eigen::Matrix3d Rd;
  Rd.col(0) = b2.cross(b3);
  Rd.col(1) = b2;
  Rd.col(2) = b3;

  const Eigen::Vector3d eR = 0.5 * vee(Rd.transpose() * R - R.transpose() * Rd);
  // Desired body rate: the yaw rate about the world vertical, expressed in the body frame.
  const Eigen::Vector3d wd = R.transpose() * Eigen::Vector3d(0, 0, ref.yaw_dot);
  const Eigen::Vector3d ew = s.angular_velocity - wd;
  const Eigen::Vector3d& w = s.angular_velocity;
  Wrench out;
  out.thrust = F.dot(R.col(2));
  out.moment = -config_.kR.cwiseProduct(eR) - config_.kw.cwiseProduct(ew) +
               w.cross(vehicle_.inertia.cwiseProduct(w));
  return out;
}

common::Status checkReference(const PositionReference& ref, const common::Aabb& bounds, double max_acceleration,
                              double max_outside, double max_speed, double max_yaw_rate) {
  if (!ref.position.allFinite() || !ref.velocity.allFinite() || !ref.acceleration.allFinite() ||
      !std::isfinite(ref.yaw) || !std::isfinite(ref.yaw_dot))
    return common::Status::Error("command has NaN or Inf fields");
  if (ref.acceleration.norm() > max_acceleration) {
    std::ostringstream os;
    os << "command acceleration " << ref.acceleration.norm() << " m/s^2 exceeds " << max_acceleration;
    return common::Status::Error(os.str());
  }
  // A finite velocity as large as 1e308 m/s made the controller's force infinite and the state NaN for good.
  if (!(ref.velocity.stableNorm() <= max_speed)) {  // stableNorm: 1e308 m/s squared would overflow
    std::ostringstream os;
    os << "command velocity " << ref.velocity.stableNorm() << " m/s exceeds " << max_speed;
    return common::Status::Error(os.str());
  }
  // A heading rate of 1e7 rad/s became a body-rate error of 1e7 rad/s in the moment: the vehicle spun up.
  if (!(std::abs(ref.yaw_dot) <= max_yaw_rate)) {
    std::ostringstream os;
    os << "command yaw rate " << ref.yaw_dot << " rad/s exceeds " << max_yaw_rate;
    return common::Status::Error(os.str());
  }
  const Eigen::Vector3d outside =
      (bounds.min - ref.position).cwiseMax(ref.position - bounds.max).cwiseMax(Eigen::Vector3d::Zero());
  if (outside.norm() > max_outside) {
    std::ostringstream os;
    os << "command position (" << ref.position.transpose() << ") lies " << outside.norm()
       << " m outside the scene bounds (limit " << max_outside << " m)";
    return common::Status::Error(os.str());
  }
  return common::Status::Ok();
}

}  // namespace go_feap::sim
