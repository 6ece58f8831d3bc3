#include "go_feap/ros/bspline_conversion.h"

#include <cmath>
#include <sstream>

namespace go_feap::ros_traj {

Bspline toMsg(const Trajectory& t) {
  Bspline msg;
  msg.order = t.position.degree();
  msg.traj_id = t.id;
  msg.start_time = t.start_time;
  const int n = t.position.numControlPoints(), p = t.position.degree();
  for (int i = 0; i < n + p + 1; ++i) msg.knots.push_back((i - p) * t.position.knotSpan());
  for (int i = 0; i < n; ++i) {
    geometry_msgs::Point pt;
    pt.x = t.position.controlPoints()(0, i);
    pt.y = t.position.controlPoints()(1, i);
    pt.z = t.position.controlPoints()(2, i);
    msg.pos_pts.push_back(pt);
  }
  for (int i = 0; i < t.yaw.numControlPoints(); ++i) msg.yaw_pts.push_back(t.yaw.controlPoints()(0, i));
  msg.yaw_dt = t.yaw.knotSpan();
  return msg;
}

common::Result<Trajectory> fromMsg(const Bspline& msg) {
  using R = common::Result<Trajectory>;
  const int p = msg.order, n = static_cast<int>(msg.pos_pts.size());
  // Degree 2 at least: a degree-1 spline's velocity jumps at every knot (no acceleration bound holds).
  if (p < 2 || p > 7) return R::Error("bspline: order " + std::to_string(p) + " is not in [2, 7]");
  if (n < p + 1) return R::Error("bspline: " + std::to_string(n) + " control points are too few for order " + std::to_string(p));
  if (static_cast<int>(msg.knots.size()) != n + p + 1)
    return R::Error("bspline: " + std::to_string(msg.knots.size()) + " knots, expected " + std::to_string(n + p + 1));
  const double dt = msg.knots[1] - msg.knots[0];
  if (!(dt > 0.0) || !std::isfinite(dt)) return R::Error("bspline: knot span must be finite and > 0");
  const double tolerance = 1e-6 * std::max(1.0, dt);
  for (std::size_t i = 1; i < msg.knots.size(); ++i)
    if (!(std::abs(msg.knots[i] - msg.knots[i - 1] - dt) <= tolerance))  // a NaN knot fails too
      return R::Error("bspline: knots are not uniform (or not finite)");
  // The spline's parameter 0 is start_time, at knot `order`: knots from 0 on would shift it order spans late.
  if (!(std::abs(msg.knots[0] + p * dt) <= tolerance))
    return R::Error("bspline: knots must start at -order * knot span (the spline's time 0 is start_time), got " +
                    std::to_string(msg.knots[0]));
  Eigen::MatrixXd q(3, n);
  for (int i = 0; i < n; ++i) q.col(i) << msg.pos_pts[i].x, msg.pos_pts[i].y, msg.pos_pts[i].z;
  if (!q.allFinite()) return R::Error("bspline: a control point is not finite");
  const int m = static_cast<int>(msg.yaw_pts.size());
  if (m < 4) return R::Error("bspline: yaw spline needs at least 4 control points");
  if (!(msg.yaw_dt > 0.0) || !std::isfinite(msg.yaw_dt)) return R::Error("bspline: yaw_dt must be finite and > 0");
  Eigen::MatrixXd y(1, m);
  for (int i = 0; i < m; ++i) y(0, i) = msg.yaw_pts[i];
  if (!y.allFinite()) return R::Error("bspline: a yaw control point is not finite");
  Trajectory t;
  t.id = msg.traj_id;
  t.start_time = msg.start_time;
  t.position = trajectory::UniformBspline(q, p, dt);
  t.yaw = trajectory::UniformBspline(y, 3, msg.yaw_dt);
  return t;
}

std::string motionProblem(const Trajectory& trajectory, double max_speed, double max_acceleration,
                          double max_yaw_rate) {
  const trajectory::UniformBspline& s = trajectory.position;
  const Eigen::MatrixXd& q = s.controlPoints();
  const double dt = s.knotSpan();
  // Velocity points (q_i+1 - q_i) / dt, acceleration points their differences over dt. Values that overflow
  // (1e308 m control points) come out inf or NaN and fail the comparisons: refused too.
  std::ostringstream why;
  for (Eigen::Index i = 0; i + 1 < q.cols(); ++i)
    if (const double v = ((q.col(i + 1) - q.col(i)) / dt).stableNorm(); !(v <= max_speed)) {
      why << "its control polygon reaches " << v << " m/s, above " << max_speed << " m/s";
      return why.str();
    }
  for (Eigen::Index i = 0; s.degree() >= 2 && i + 2 < q.cols(); ++i)
    if (const double a = ((q.col(i + 2) - 2.0 * q.col(i + 1) + q.col(i)) / (dt * dt)).stableNorm();
        !(a <= max_acceleration)) {
      why << "its control polygon reaches " << a << " m/s^2, above " << max_acceleration << " m/s^2";
      return why.str();
    }
  // The heading likewise: its rate is bounded by the yaw polygon's differences over the yaw knot span (a
  // rate of 1e7 rad/s would turn the commanded heading arbitrarily between two commands, and 1e308 rad
  // points make the rate inf - inf = NaN).
  const Eigen::MatrixXd& y = trajectory.yaw.controlPoints();
  const double yaw_dt = trajectory.yaw.knotSpan();
  for (Eigen::Index i = 0; i + 1 < y.cols(); ++i)
    if (const double r = std::abs((y(0, i + 1) - y(0, i)) / yaw_dt); !(r <= max_yaw_rate)) {
      why << "its yaw control polygon turns at " << r << " rad/s, above " << max_yaw_rate << " rad/s";
      return why.str();
    }
  return "";
}

}  // namespace go_feap::ros_traj
