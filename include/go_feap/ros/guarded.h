// Callbacks that cannot end the nodelet manager. An exception escaping a subscription, timer or service
// callback is not caught by roscpp: it reaches std::terminate and takes down the whole nodelet manager,
// with every nodelet and the map in it (a status message once did that to the chain through the
// metrics recorder). The nodelets subscribe through these helpers: such an exception is logged as an
// error naming the nodelet, the callback and what was thrown (at most once a second for each callback of
// each nodelet, the first at once), and the nodelet goes on with the next message. Only std::exception is
// caught: anything else (as boost::thread_interrupted, with which the nodelet manager stops its worker
// threads) passes on.
#pragma once

#include <ros/ros.h>

#include <boost/function.hpp>
#include <boost/shared_ptr.hpp>
#include <cstdint>
#include <exception>
#include <memory>
#include <string>
#include <utility>

#include "go_feap/ros/log_throttle.h"

namespace go_feap::ros_guard {

/// Runs fn(); a std::exception escaping it is logged (who: the nodelet, what: the callback; at most once a
/// second for each `what` in `throttle`) and swallowed. Returns whether fn() ran to its end.
template <typename Fn>
bool run(const std::string& who, const std::string& what, ros_log::Throttle& throttle, Fn&& fn) {
  try {
    std::forward<Fn>(fn)();
    return true;
  } catch (const std::exception& e) {
    if (throttle.pass(what, 1.0, ros::Time::now().toSec()))
      ROS_ERROR_STREAM_NAMED(who, who << ": " << what << " aborted by an exception: " << e.what()
                                      << "; the nodelet goes on with the next one");
  }
  return false;
}

/// `object`'s member `callback` as a subscription callback under run().
template <typename T, typename M>
boost::function<void(const boost::shared_ptr<M const>&)> wrap(
    const std::string& who, const std::string& what, void (T::*callback)(const boost::shared_ptr<M const>&),
    T* object) {
  return [who, what, callback, object, throttle = std::make_shared<ros_log::Throttle>()](
             const boost::shared_ptr<M const>& msg) { run(who, what, *throttle, [&] { (object->*callback)(msg); }); };
}

/// nh.subscribe(topic, queue, callback, object, hints), the callback under run().
template <typename T, typename M>
ros::Subscriber subscribe(ros::NodeHandle& nh, const std::string& who, const std::string& topic,
                          std::uint32_t queue, void (T::*callback)(const boost::shared_ptr<M const>&),
                          T* object, const ros::TransportHints& hints = ros::TransportHints()) {
  return nh.subscribe<M>(topic, queue, wrap(who, "the callback of '" + topic + "'", callback, object),
                         ros::VoidConstPtr(), hints);
}

/// nh.createTimer(period, callback, object), the callback under run().
template <typename T>
ros::Timer timer(ros::NodeHandle& nh, const std::string& who, const ros::Duration& period,
                 void (T::*callback)(const ros::TimerEvent&), T* object) {
  return nh.createTimer(period, boost::function<void(const ros::TimerEvent&)>(
                                    [who, callback, object, throttle = std::make_shared<ros_log::Throttle>()](
                                        const ros::TimerEvent& e) {
                                      run(who, "the timer callback", *throttle, [&] { (object->*callback)(e); });
                                    }));
}

/// nh.advertiseService(name, callback, object), the callback under run(): a call it aborts fails.
template <typename T, typename Req, typename Res>
ros::ServiceServer service(ros::NodeHandle& nh, const std::string& who, const std::string& name,
                           bool (T::*callback)(Req&, Res&), T* object) {
  return nh.advertiseService<Req, Res>(
      name, boost::function<bool(Req&, Res&)>([who, name, callback, object,
                                               throttle = std::make_shared<ros_log::Throttle>()](Req& req, Res& res) {
        bool ok = false;
        run(who, "the service '" + name + "'", *throttle, [&] { ok = (object->*callback)(req, res); });
        return ok;
      }));
}

}  // namespace go_feap::ros_guard
