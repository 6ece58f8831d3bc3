#include "go_feap/sim/vehicle.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace go_feap::sim {

SimulatedVehicle::SimulatedVehicle(const QuadrotorParams& params, const So3ControllerConfig& control)
    : quad_(params), controller_(control, params) {}

void SimulatedVehicle::reset(const Eigen::Vector3d& position, double yaw, double time) {
  QuadrotorState s;
  s.position = position;
  s.attitude = Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  quad_.setState(s);
  time_ = time;
}

void SimulatedVehicle::advance(double duration, const PositionReference& ref) {
  // An infinite duration never ended; zero, negative or NaN advance nothing, as before.
  if (std::isinf(duration) && duration > 0.0)
    throw std::invalid_argument("SimulatedVehicle::advance: duration must be finite");
  const double h = 1.0 / quad_.params().dynamics_rate;
  double left = duration;
  while (left > 1e-12) {
    const double dt = std::min(h, left);
    const Wrench wanted = controller_.compute(quad_.state(), ref);
    last_wanted_rotors_ = quad_.rotorThrusts(wanted);
    last_rotors_ = quad_.rotorThrusts(quad_.step(wanted, dt));
    left -= dt;
    time_ += dt;
  }
}

}  // namespace go_feap::sim
