// Geometric controller + rigid-body dynamics in closed loop.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "go_feap/sim/pacer.h"
#include "go_feap/sim/vehicle.h"

using namespace go_feap::sim;

namespace {

constexpr double kDt = 0.01;  // reference update period (s); the dynamics step inside is 2 ms

struct Flight {
  std::vector<double> t;
  std::vector<Eigen::Vector3d> p, p_ref;
  std::vector<double> yaw, yaw_ref;
  double max_rotor = 0.0, min_rotor = 1e9, max_wanted = 0.0, min_wanted = 1e9;
};

double yawOf(const QuadrotorState& s) {
  const Eigen::Vector3d x = s.attitude * Eigen::Vector3d::UnitX();
  return std::atan2(x.y(), x.x());
}

double wrap(double a) { return std::atan2(std::sin(a), std::cos(a)); }

Flight fly(SimulatedVehicle& v, double duration, const std::function<PositionReference(double)>& ref) {
  Flight r;
  for (double t = 0.0; t < duration - 1e-9; t += kDt) {
    const PositionReference pr = ref(v.time());
    v.advance(kDt, pr);
    r.t.push_back(v.time());
    r.p.push_back(v.state().position);
    r.p_ref.push_back(ref(v.time()).position);
    r.yaw.push_back(yawOf(v.state()));
    r.yaw_ref.push_back(ref(v.time()).yaw);
    r.max_rotor = std::max(r.max_rotor, v.lastRotorThrusts().maxCoeff());
    r.min_rotor = std::min(r.min_rotor, v.lastRotorThrusts().minCoeff());
    r.max_wanted = std::max(r.max_wanted, v.lastWantedRotorThrusts().maxCoeff());
    r.min_wanted = std::min(r.min_wanted, v.lastWantedRotorThrusts().minCoeff());
  }
  return r;
}

void expectWithinMotorLimits(const Flight& r, const QuadrotorParams& p) {
  EXPECT_LE(r.max_rotor, p.motor_max_thrust + 1e-9);
  EXPECT_GE(r.min_rotor, p.motor_min_thrust - 1e-9);
}

}  // namespace

TEST(Vehicle, HoverStaysWithinTwoCentimetres) {
  SimulatedVehicle v{QuadrotorParams(), So3ControllerConfig()};
  v.reset(Eigen::Vector3d(1, 2, 1), 0.3);
  PositionReference ref;
  ref.position = Eigen::Vector3d(1, 2, 1);
  ref.yaw = 0.3;
  const Flight r = fly(v, 10.0, [&](double) { return ref; });
  for (const auto& p : r.p) ASSERT_LT((p - ref.position).norm(), 0.02);
  // Hovering needs m g / 4 per rotor, nowhere near the limits.
  EXPECT_NEAR(r.max_wanted, QuadrotorParams().mass * 9.81 / 4, 0.05);
  expectWithinMotorLimits(r, QuadrotorParams());
}

TEST(Vehicle, OneMetreStepSettlesWithinThreeSecondsWithSmallOvershoot) {
  for (int axis = 0; axis < 3; ++axis) {
    SimulatedVehicle v{QuadrotorParams(), So3ControllerConfig()};
    v.reset(Eigen::Vector3d(0, 0, 1), 0.0);
    PositionReference ref;
    ref.position = Eigen::Vector3d(0, 0, 1) + Eigen::Vector3d::Unit(axis);
    const Flight r = fly(v, 6.0, [&](double) { return ref; });
    double overshoot = 0.0;
    for (std::size_t i = 0; i < r.t.size(); ++i) {
      const double progress = r.p[i][axis] - (axis == 2 ? 1.0 : 0.0);
      overshoot = std::max(overshoot, progress - 1.0);
      if (r.t[i] >= 3.0) {
        ASSERT_LT((r.p[i] - ref.position).norm(), 0.05) << "axis " << axis << " t " << r.t[i];
      }
    }
    EXPECT_LT(overshoot, 0.10) << "axis " << axis;
    expectWithinMotorLimits(r, QuadrotorParams());
  }
}

TEST(Vehicle, TracksA2MetrePerSecondCircle) {
  const double radius = 2.0, speed = 2.0, w = speed / radius;
  auto circle = [&](double t) {
    PositionReference ref;
    ref.position = Eigen::Vector3d(radius * std::cos(w * t), radius * std::sin(w * t), 1.5);
    ref.velocity = Eigen::Vector3d(-speed * std::sin(w * t), speed * std::cos(w * t), 0);
    ref.acceleration = -w * w * Eigen::Vector3d(ref.position.x(), ref.position.y(), 0);
    ref.yaw = wrap(w * t + M_PI / 2);
    ref.yaw_dot = w;
    return ref;
  };
  SimulatedVehicle v{QuadrotorParams(), So3ControllerConfig()};
  // Start on the circle, already moving with it, tilted to hold the centripetal force.
  QuadrotorState start;
  start.position = circle(0).position;
  start.velocity = circle(0).velocity;
  const Eigen::Vector3d thrust_dir = (circle(0).acceleration + Eigen::Vector3d(0, 0, 9.81)).normalized();
  start.attitude = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), thrust_dir) *
                   Eigen::Quaterniond(Eigen::AngleAxisd(circle(0).yaw, Eigen::Vector3d::UnitZ()));
  start.angular_velocity = start.attitude.inverse() * Eigen::Vector3d(0, 0, w);
  v.setState(start);
  const Flight r = fly(v, 2.0 * (2 * M_PI / w), circle);
  double sq = 0.0;
  for (std::size_t i = 0; i < r.p.size(); ++i) sq += (r.p[i] - r.p_ref[i]).squaredNorm();
  const double rms = std::sqrt(sq / r.p.size());
  EXPECT_LT(rms, 0.10);
  std::cout << "circle RMS position error " << rms << " m\n";
  // Steady turning needs no saturation.
  EXPECT_LT(r.max_wanted, QuadrotorParams().motor_max_thrust);
  EXPECT_GT(r.min_wanted, QuadrotorParams().motor_min_thrust);
  expectWithinMotorLimits(r, QuadrotorParams());
}

TEST(Vehicle, YawFollowsAOneRadianPerSecondRamp) {
  SimulatedVehicle v{QuadrotorParams(), So3ControllerConfig()};
  v.reset(Eigen::Vector3d(0, 0, 1), 0.0);
  auto ramp = [](double t) {
    PositionReference ref;
    ref.position = Eigen::Vector3d(0, 0, 1);
    ref.yaw = wrap(t);
    ref.yaw_dot = 1.0;
    return ref;
  };
  const Flight r = fly(v, 8.0, ramp);
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    if (r.t[i] > 2.0) {
      ASSERT_LT(std::abs(wrap(r.yaw[i] - r.yaw_ref[i])), 0.05) << "t " << r.t[i];
    }
    ASSERT_LT((r.p[i] - Eigen::Vector3d(0, 0, 1)).norm(), 0.02);
  }
  expectWithinMotorLimits(r, QuadrotorParams());
}

TEST(Quadrotor, SaturationClampsEachRotorAndFreeFallWithoutThrust) {
  Quadrotor q{QuadrotorParams()};
  const Wrench huge{100.0, Eigen::Vector3d(5, -5, 1)};
  const Eigen::Vector4d applied = q.rotorThrusts(q.saturate(huge));
  EXPECT_LE(applied.maxCoeff(), q.params().motor_max_thrust + 1e-9);
  EXPECT_GE(applied.minCoeff(), q.params().motor_min_thrust - 1e-9);
  // Within limits the allocation is exact.
  const Wrench ok{10.0, Eigen::Vector3d(0.05, -0.02, 0.01)};
  const Wrench back = q.saturate(ok);
  EXPECT_NEAR(back.thrust, ok.thrust, 1e-9);
  EXPECT_LT((back.moment - ok.moment).norm(), 1e-9);
  // No thrust: free fall, z = -g t^2 / 2 (RK4 is exact for constant acceleration).
  for (int i = 0; i < 500; ++i) q.step(Wrench{0.0, Eigen::Vector3d::Zero()}, 0.002);
  EXPECT_NEAR(q.state().position.z(), -0.5 * 9.81 * 1.0, 1e-9);
}

// Past the motor limits the roll and pitch moments come first, then the collective thrust, then yaw.
TEST(Quadrotor, SaturationKeepsRollAndPitchThenThrustThenYaw) {
  Quadrotor q{QuadrotorParams()};
  const QuadrotorParams& p = q.params();
  auto within = [&](const Wrench& w) {
    const Eigen::Vector4d f = q.rotorThrusts(w);
    return f.maxCoeff() <= p.motor_max_thrust + 1e-9 && f.minCoeff() >= p.motor_min_thrust - 1e-9;
  };
  // All rotors asked for more than their maximum, and a pitch moment: the moment is kept whole, the thrust
  // is what is left (each rotor clamped on its own would have given no moment at all), all of it: the
  // moment M takes M / (4 d) from each front rotor and gives it to each rear one (d the arm's projection),
  // the rear ones at their maximum, so the thrust is 4 max - M / d.
  const Wrench climb{4.0 * p.motor_max_thrust + 5.0, Eigen::Vector3d(0.0, 0.3, 0.0)};
  const Wrench a = q.saturate(climb);
  EXPECT_TRUE(within(a));
  EXPECT_LT((a.moment - climb.moment).norm(), 1e-9);
  EXPECT_NEAR(a.thrust, 4.0 * p.motor_max_thrust - 0.3 / (p.arm_length / std::sqrt(2.0)), 1e-9);
  EXPECT_NEAR(q.rotorThrusts(a).maxCoeff(), p.motor_max_thrust, 1e-9);
  // More roll and pitch than the rotors can span: the direction is kept, the size scaled down.
  const Wrench tumble{10.0, Eigen::Vector3d(50.0, -25.0, 0.0)};
  const Wrench b = q.saturate(tumble);
  EXPECT_TRUE(within(b));
  EXPECT_NEAR(b.moment.x() / b.moment.y(), -2.0, 1e-9);
  EXPECT_NEAR(b.moment.z(), 0.0, 1e-9);
  const Eigen::Vector4d fb = q.rotorThrusts(b);
  EXPECT_NEAR(fb.maxCoeff() - fb.minCoeff(), p.motor_max_thrust - p.motor_min_thrust, 1e-9);
  // Hover thrust and a yaw moment beyond what is left: the thrust is kept, the yaw moment reduced.
  const Wrench spin{p.mass * p.gravity, Eigen::Vector3d(0.0, 0.0, 5.0)};
  const Wrench c = q.saturate(spin);
  EXPECT_TRUE(within(c));
  EXPECT_NEAR(c.thrust, spin.thrust, 1e-9);
  EXPECT_GT(c.moment.z(), 0.0);
  EXPECT_LT(c.moment.z(), 5.0);
  EXPECT_LT(c.moment.head<2>().norm(), 1e-9);
  EXPECT_TRUE(!within(Wrench{c.thrust, Eigen::Vector3d(0.0, 0.0, c.moment.z() * 1.01)}))
      << "the yaw moment could have been larger";
  // Low thrust (0.5 N a rotor) and a yaw moment: the motors' minimum bounds the moment, the thrust is kept.
  const Wrench low{2.0, Eigen::Vector3d(0.0, 0.0, 1.0)};
  const Wrench d = q.saturate(low);
  EXPECT_TRUE(within(d));
  EXPECT_NEAR(d.thrust, low.thrust, 1e-9);
  EXPECT_GT(d.moment.z(), 0.0);
  EXPECT_TRUE(!within(Wrench{d.thrust, Eigen::Vector3d(0.0, 0.0, d.moment.z() * 1.01)}))
      << "the yaw moment could have been larger";
}

// Linear drag decays the velocity at linear_drag / mass: coasting with no thrust from 1 m/s along x, a 2 kg
// vehicle with 1 kg/s of drag follows v_x = exp(-t / 2), x = 2 (1 - exp(-t / 2)), and falls with
// v_z = -(g m / c) (1 - exp(-c t / m)).
TEST(Quadrotor, DragDecaysTheVelocityAtDragOverMass) {
  QuadrotorParams p;
  p.mass = 2.0;
  p.motor_max_thrust = 6.0;
  p.linear_drag = 1.0;
  ASSERT_TRUE(p.validate()) << p.validate().message();
  Quadrotor q{p};
  QuadrotorState s;
  s.velocity = Eigen::Vector3d(1.0, 0.0, 0.0);
  q.setState(s);
  for (int i = 0; i < 500; ++i) q.step(Wrench{0.0, Eigen::Vector3d::Zero()}, 0.002);
  const double lambda = p.linear_drag / p.mass, t = 1.0;
  EXPECT_NEAR(q.state().velocity.x(), std::exp(-lambda * t), 1e-9);
  EXPECT_NEAR(q.state().position.x(), (1.0 - std::exp(-lambda * t)) / lambda, 1e-9);
  EXPECT_NEAR(q.state().velocity.z(), -p.gravity / lambda * (1.0 - std::exp(-lambda * t)), 1e-9);
}

// A reference many metres away (a hold after a refused plan, a hand-sent goal): the vehicle stays
// within its tilt limit and arrives, instead of pitching over with every rotor at its maximum.
TEST(Vehicle, AReferenceManyMetresAwayIsReachedUpright) {
  for (const Eigen::Vector3d& step : {Eigen::Vector3d(8, 0, -10), Eigen::Vector3d(15, 0, -10),
                                      Eigen::Vector3d(0, 10, -10), Eigen::Vector3d(10, 0, 10)}) {
    SimulatedVehicle v{QuadrotorParams(), So3ControllerConfig()};
    const Eigen::Vector3d start(0, 0, 12);
    v.reset(start, 0.0);
    PositionReference ref;
    ref.position = start + step;
    double max_tilt = 0.0, lowest = start.z(), max_rotor = 0.0;
    for (int i = 0; i < 1500; ++i) {  // 15 s
      v.advance(kDt, ref);
      const double cos_tilt = (v.state().attitude * Eigen::Vector3d::UnitZ()).z();
      max_tilt = std::max(max_tilt, std::acos(std::clamp(cos_tilt, -1.0, 1.0)));
      lowest = std::min(lowest, v.state().position.z());
      max_rotor = std::max(max_rotor, v.lastRotorThrusts().maxCoeff());
    }
    const std::string what = "step (" + std::to_string(step.x()) + ", " + std::to_string(step.y()) + ", " +
                             std::to_string(step.z()) + ")";
    EXPECT_LT(max_tilt, So3ControllerConfig().max_tilt + 0.35) << what;
    // Falling 10 m the vehicle dips below the new height before it stops (1.1-1.7 m with these gains); with
    // each rotor clamped on its own it pitched over and fell 9-24 m below it.
    EXPECT_GT(lowest, std::min(start.z(), ref.position.z()) - 2.0) << what;
    EXPECT_LT((v.state().position - ref.position).norm(), 0.05) << what;
    EXPECT_LE(max_rotor, QuadrotorParams().motor_max_thrust + 1e-9) << what;
  }
}

// The tilt limit, exactly: at rest, 15 m short of the reference in x and already tilted max_tilt towards it
// (heading x), the vehicle holds its attitude (the thrust it asks for is max_tilt off vertical: no moment)
// and asks for the thrust that keeps its height, m g / cos(max_tilt).
TEST(So3Controller, TheThrustAimedAtAFarReferenceIsTiltedExactlyMaxTilt) {
  const QuadrotorParams params;
  const So3ControllerConfig config;
  const So3Controller controller(config, params);
  QuadrotorState s;
  s.attitude = Eigen::AngleAxisd(config.max_tilt, Eigen::Vector3d::UnitY());  // body z towards +x
  PositionReference ref;
  ref.position = Eigen::Vector3d(15.0, 0.0, 0.0);
  const Wrench w = controller.compute(s, ref);
  EXPECT_LT(w.moment.norm(), 1e-9) << w.moment.transpose();
  EXPECT_NEAR(w.thrust, params.mass * params.gravity / std::cos(config.max_tilt), 1e-9);
  // Tilted a little less or more, it turns towards max_tilt: a pitch moment of the sign that closes the gap.
  for (const double off : {-0.05, 0.05}) {
    s.attitude = Eigen::AngleAxisd(config.max_tilt + off, Eigen::Vector3d::UnitY());
    const Wrench turn = controller.compute(s, ref);
    EXPECT_LT(turn.moment.y() * off, 0.0) << "off " << off << ": " << turn.moment.transpose();
  }
}

// The feed-forwards the reference asks for: the drag of the reference velocity (linear_drag times it, on top of
// m (a + g)), and the gyroscopic moment w x (J w) of the present body rate. On a vehicle with drag 0.5 flying at
// the reference's 2 m/s along x, attitude along the wanted force (1, 0, m g): no attitude moment and a thrust of
// |F|; spinning at (0.3, 2, 0.1) rad/s on the reference, upright: the moment is -kw w + w x (J w) exactly.
TEST(So3Controller, FeedsForwardTheReferenceDragAndTheGyroscopicMoment) {
  QuadrotorParams params;
  params.linear_drag = 0.5;
  ASSERT_TRUE(params.validate().ok()) << params.validate().message();
  const So3ControllerConfig config;
  const So3Controller controller(config, params);
  QuadrotorState s;
  PositionReference ref;
  s.velocity = ref.velocity = Eigen::Vector3d(2.0, 0.0, 0.0);
  const Eigen::Vector3d F(params.linear_drag * 2.0, 0.0, params.mass * params.gravity);
  s.attitude = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), F);
  const Wrench flying = controller.compute(s, ref);
  EXPECT_LT(flying.moment.norm(), 1e-9) << flying.moment.transpose();
  EXPECT_NEAR(flying.thrust, F.norm(), 1e-9);

  QuadrotorState spinning;
  spinning.angular_velocity = Eigen::Vector3d(0.3, 2.0, 0.1);
  const PositionReference here;
  const Eigen::Vector3d& w = spinning.angular_velocity;
  const Eigen::Vector3d expected = -config.kw.cwiseProduct(w) + w.cross(params.inertia.cwiseProduct(w));
  const Wrench spin = controller.compute(spinning, here);
  EXPECT_LT((spin.moment - expected).norm(), 1e-12) << spin.moment.transpose() << " against " << expected.transpose();
  EXPECT_GT(w.cross(params.inertia.cwiseProduct(w)).norm(), 1e-4);  // the gyroscopic part is there to see
}

// The heading rate is fed forward about the world vertical: at a roll of 30 deg the yaw rate asked for
// changes the moment by the rate gains times the world z axis in the body frame times the rate (about the
// body z axis alone, the vehicle would turn about its tilted axis).
TEST(So3Controller, TheYawRateIsFedForwardAboutTheWorldVertical) {
  const QuadrotorParams params;
  const So3ControllerConfig config;
  const So3Controller controller(config, params);
  QuadrotorState s;
  s.position = Eigen::Vector3d(0.2, -0.1, 1.0);
  s.velocity = Eigen::Vector3d(0.3, 0.1, 0.0);
  s.attitude = Eigen::AngleAxisd(M_PI / 6.0, Eigen::Vector3d::UnitX());
  s.angular_velocity = Eigen::Vector3d(0.1, -0.2, 0.3);
  PositionReference still, turning;
  still.position = turning.position = Eigen::Vector3d(0.0, 0.0, 1.0);
  turning.yaw_dot = 0.8;
  const Eigen::Vector3d difference = controller.compute(s, turning).moment - controller.compute(s, still).moment;
  const Eigen::Vector3d z_in_body = s.attitude.inverse() * Eigen::Vector3d::UnitZ();
  EXPECT_LT((difference - config.kw.cwiseProduct(z_in_body) * turning.yaw_dot).norm(), 1e-12) << difference.transpose();
  EXPECT_GT(std::abs(difference.y()), 0.01);  // the roll puts part of it about the body y axis
}

// The heading error's moment vanishes at half a turn in the geometric controller; the vehicle turns anyway.
TEST(Vehicle, AHeadingHalfATurnRoundIsReached) {
  for (const double start_yaw : {0.3, 0.0, -2.0}) {
    SimulatedVehicle v{QuadrotorParams(), So3ControllerConfig()};
    v.reset(Eigen::Vector3d(0, 0, 1), start_yaw);
    PositionReference ref;
    ref.position = Eigen::Vector3d(0, 0, 1);
    ref.yaw = start_yaw + M_PI;
    const Flight r = fly(v, 5.0, [&](double) { return ref; });
    EXPECT_LT(std::abs(wrap(r.yaw.back() - ref.yaw)), 0.02) << "from yaw " << start_yaw;
    for (const auto& p : r.p) ASSERT_LT((p - ref.position).norm(), 0.05) << "from yaw " << start_yaw;
  }
}

TEST(Quadrotor, AStepThatIsNotAPositiveFiniteTimeIsRefused) {
  Quadrotor q{QuadrotorParams()};
  const Wrench hover{q.params().mass * q.params().gravity, Eigen::Vector3d::Zero()};
  for (const double dt : {0.0, -0.002, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()})
    EXPECT_THROW(q.step(hover, dt), std::invalid_argument) << "dt " << dt;
  EXPECT_TRUE(q.state().finite());
  EXPECT_EQ(q.state().position, Eigen::Vector3d::Zero());
  SimulatedVehicle v{QuadrotorParams(), So3ControllerConfig()};
  v.reset(Eigen::Vector3d(0, 0, 1), 0.0);
  PositionReference ref;
  ref.position = Eigen::Vector3d(0, 0, 1);
  EXPECT_THROW(v.advance(std::numeric_limits<double>::infinity(), ref), std::invalid_argument);
  v.advance(-1.0, ref);  // nothing to advance
  EXPECT_EQ(v.time(), 0.0);
}

// A duration that is not a whole number of dynamics steps ends with a shorter step: the vehicle's clock and
// state are those of the exact split (2.5 steps: 0.005 s at 500 Hz = 0.002 + 0.002 + 0.001 s), not one step more.
TEST(Vehicle, AdvanceEndsWithAShorterStepAtTheDurationAsked) {
  for (const double rate : {500.0, 700.0}) {
    QuadrotorParams params;
    params.dynamics_rate = rate;
    PositionReference ref;
    ref.position = Eigen::Vector3d(1.0, -0.5, 1.5);  // a climb and a sidestep: the state changes every step
    SimulatedVehicle whole{params, So3ControllerConfig()}, split{params, So3ControllerConfig()};
    whole.reset(Eigen::Vector3d(0, 0, 1), 0.0);
    split.reset(Eigen::Vector3d(0, 0, 1), 0.0);
    const double h = 1.0 / rate, duration = 2.5 * h;
    whole.advance(duration, ref);
    split.advance(h, ref);
    split.advance(h, ref);
    split.advance(0.5 * h, ref);
    EXPECT_NEAR(whole.time(), duration, 1e-15) << rate << " Hz";
    EXPECT_NEAR(split.time(), duration, 1e-15) << rate << " Hz";
    EXPECT_TRUE(whole.state().position.isApprox(split.state().position, 1e-12)) << rate << " Hz";
    EXPECT_TRUE(whole.state().velocity.isApprox(split.state().velocity, 1e-12)) << rate << " Hz";
    EXPECT_GT(whole.state().velocity.norm(), 0.0);
  }
}

TEST(Quadrotor, TorqueFreeSpinConservesAngularMomentum) {
  Quadrotor q{QuadrotorParams()};
  QuadrotorState s;
  s.angular_velocity = Eigen::Vector3d(0.3, 2.0, 0.1);
  q.setState(s);
  auto momentum = [&] {
    const auto& st = q.state();
    return (st.attitude * q.params().inertia.cwiseProduct(st.angular_velocity)).eval();
  };
  const Eigen::Vector3d L0 = momentum();
  for (int i = 0; i < 1000; ++i) q.step(Wrench{0.0, Eigen::Vector3d::Zero()}, 0.002);
  EXPECT_LT((momentum() - L0).norm(), 1e-6 * L0.norm() + 1e-9);
}

TEST(Reference, BadCommandsAreRefusedWithAReason) {
  const go_feap::common::Aabb bounds{Eigen::Vector3d(-10, -5, 0), Eigen::Vector3d(10, 5, 3)};
  PositionReference ok;
  ok.position = Eigen::Vector3d(1, 1, 1);
  EXPECT_TRUE(checkReference(ok, bounds));
  PositionReference nan = ok;
  nan.velocity.x() = std::nan("");
  EXPECT_NE(checkReference(nan, bounds).message().find("NaN"), std::string::npos);
  PositionReference acc = ok;
  acc.acceleration = Eigen::Vector3d(0, 0, 60);
  EXPECT_NE(checkReference(acc, bounds).message().find("acceleration"), std::string::npos);
  PositionReference fast = ok;
  fast.velocity = Eigen::Vector3d(0, 0, 1e308);  // finite, and it made the controller's state NaN for good
  EXPECT_NE(checkReference(fast, bounds).message().find("velocity 1e+308 m/s exceeds 20"), std::string::npos)
      << checkReference(fast, bounds).message();
  fast.velocity = Eigen::Vector3d(12, 0, 16);  // 20 m/s: accepted
  EXPECT_TRUE(checkReference(fast, bounds));
  PositionReference far = ok;
  far.position = Eigen::Vector3d(25, 0, 1);
  EXPECT_NE(checkReference(far, bounds).message().find("outside"), std::string::npos);
  far.position = Eigen::Vector3d(18, 13, 1);  // 8 m outside on two axes: 11.3 m away
  EXPECT_NE(checkReference(far, bounds).message().find("outside"), std::string::npos);
  far.position = Eigen::Vector3d(17, 12, 1);  // 7 m on two axes: 9.9 m away, accepted
  EXPECT_TRUE(checkReference(far, bounds));
  far.position = Eigen::Vector3d(19, 0, 1);  // 9 m outside: still accepted
  EXPECT_TRUE(checkReference(far, bounds));
  for (const Eigen::Vector3d& below : {Eigen::Vector3d(-25, 0, 1), Eigen::Vector3d(1, 1, -11)}) {  // past the minimum
    far.position = below;
    EXPECT_NE(checkReference(far, bounds).message().find("outside"), std::string::npos) << below.transpose();
  }
  far.position = Eigen::Vector3d(-19, 0, 1);
  EXPECT_TRUE(checkReference(far, bounds));
  PositionReference spin = ok;
  spin.yaw_dot = -1e7;  // finite, and the controller's moment spun the vehicle up
  EXPECT_NE(checkReference(spin, bounds).message().find("yaw rate -1e+07 rad/s exceeds 20"), std::string::npos)
      << checkReference(spin, bounds).message();
  spin.yaw_dot = -20.0;  // at the limit: accepted
  EXPECT_TRUE(checkReference(spin, bounds));
}

TEST(Config, InvalidValuesNameTheKey) {
  QuadrotorParams p;
  p.motor_max_thrust = 2.0;
  EXPECT_NE(p.validate().message().find("motor_max_thrust"), std::string::npos);
  p = QuadrotorParams();
  p.dynamics_rate = 100;
  EXPECT_NE(p.validate().message().find("dynamics_rate"), std::string::npos);
  p.dynamics_rate = 1e15;  // one simulated step never ended
  EXPECT_NE(p.validate().message().find("dynamics_rate"), std::string::npos);
  for (const Eigen::Vector3d& inertia : {Eigen::Vector3d(2.64e-3, 0.0, 4.96e-3), Eigen::Vector3d(2.64e-3, -1e-3, 4.96e-3),
                                         Eigen::Vector3d(std::numeric_limits<double>::infinity(), 2.64e-3, 4.96e-3)}) {
    p = QuadrotorParams();
    p.inertia = inertia;  // a zero component divides the dynamics by zero
    EXPECT_NE(p.validate().message().find("inertia"), std::string::npos) << inertia.transpose();
  }
  So3ControllerConfig c;
  c.kv.y() = -1;
  EXPECT_NE(c.validate().message().find("kv"), std::string::npos);
  // Past pi / 2 the tangent of the tilt limit turns negative and the horizontal force points away.
  for (double tilt : {1.4, 2.0, 0.05}) {
    c = So3ControllerConfig();
    c.max_tilt = tilt;
    EXPECT_NE(c.validate().message().find("max_tilt"), std::string::npos) << tilt;
  }
  c.max_tilt = 1.39;
  EXPECT_TRUE(c.validate()) << c.validate().message();
}

// Values that cannot fly are refused by name: infinite ones (an infinite arm length or torque coefficient
// made the rotor allocation singular, an infinite drag the state NaN), a drag too stiff for the RK4 step,
// and a minimum thrust that leaves no hover. A drag at the bound flies towards a reference, finite
// (slowly: 500 1/s of decay against the controller's gains).
TEST(Config, ValuesThatCannotFlyAreRefusedByName) {
  const double inf = std::numeric_limits<double>::infinity();
  const std::pair<const char*, std::function<void(QuadrotorParams&)>> bad[] = {
      {"mass", [&](QuadrotorParams& p) { p.mass = inf; }},
      {"arm_length", [&](QuadrotorParams& p) { p.arm_length = inf; }},
      {"torque_coefficient", [&](QuadrotorParams& p) { p.torque_coefficient = inf; }},
      {"gravity", [&](QuadrotorParams& p) { p.gravity = inf; }},
      {"motor_max_thrust", [&](QuadrotorParams& p) { p.motor_max_thrust = inf; }},
      {"motor_min_thrust", [&](QuadrotorParams& p) { p.motor_min_thrust = inf; }},
      {"motor_min_thrust", [&](QuadrotorParams& p) { p.motor_min_thrust = 3.0; }},  // 4 x 3 N > 0.98 kg g
      {"linear_drag", [&](QuadrotorParams& p) { p.linear_drag = inf; }},
      {"linear_drag", [&](QuadrotorParams& p) { p.linear_drag = 5000.0; }},
      {"linear_drag", [&](QuadrotorParams& p) { p.linear_drag = -0.5; }},  // a push, not a drag
      {"motor_min_thrust", [&](QuadrotorParams& p) { p.motor_min_thrust = -0.1; }}};
  for (const auto& [key, spoil] : bad) {
    QuadrotorParams p;
    spoil(p);
    const auto st = p.validate();
    EXPECT_FALSE(st.ok()) << key;
    EXPECT_NE(st.message().find(key), std::string::npos) << key << ": " << st.message();
  }
  QuadrotorParams p;
  p.linear_drag = p.mass * p.dynamics_rate;
  ASSERT_TRUE(p.validate()) << p.validate().message();
  SimulatedVehicle v{p, So3ControllerConfig()};
  v.reset(Eigen::Vector3d(0, 0, 1), 0.0);
  PositionReference ref;
  ref.position = Eigen::Vector3d(0.5, 0, 1);
  const Flight r = fly(v, 5.0, [&](double) { return ref; });
  for (const Eigen::Vector3d& x : r.p) ASSERT_TRUE(x.allFinite());
  EXPECT_LT((r.p.back() - ref.position).norm(), 0.49) << "no headway against the drag (about 4 cm in 5 s)";
}

// Simulated time is paced at the rate factor against wall time; after a stall longer than max_lag it goes on
// from where the wall clock is, at the rate factor, instead of running the stalled time without a pause
// (planners computing on wall time could not answer, their commands timed out). A lag within max_lag is
// caught up.
TEST(WallPacer, DropsALagOverMaxLagAndCatchesUpASmallerOne) {
  go_feap::sim::WallPacer pacer(2.0, 0.2);
  EXPECT_DOUBLE_EQ(pacer.due(1.0), 0.5);
  EXPECT_DOUBLE_EQ(pacer.settle(1.0, 0.6), 0.0);  // 0.1 s late: caught up
  EXPECT_DOUBLE_EQ(pacer.due(1.2), 0.6);
  // A 3 s stall after simulated 1.2 s: the wall clock says 3.6 s. Dropped, and paced from there.
  EXPECT_DOUBLE_EQ(pacer.settle(1.2, 3.6), 3.0);
  EXPECT_DOUBLE_EQ(pacer.due(1.2), 3.6);
  EXPECT_DOUBLE_EQ(pacer.due(3.2), 4.6);  // 2 simulated s later, 1 wall s (rate factor 2)
  EXPECT_DOUBLE_EQ(pacer.settle(3.2, 4.6), 0.0);
}

// The heading is the yaw of a Z-Y-X (yaw, pitch, roll) attitude, whatever the tilt, on (-pi, pi].
TEST(QuadrotorState, HeadingIsTheYawOfTheAttitude) {
  go_feap::sim::QuadrotorState s;
  for (const double yaw : {0.0, 1.0, 2.5, -3.0, M_PI}) {
    s.attitude = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()) *
                 Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitX());
    EXPECT_NEAR(s.heading(), yaw, 1e-12) << yaw;
  }
}
