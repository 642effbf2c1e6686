#include "attitude_propagator/ros/live_parameters.h"

#include <stdexcept>
#include <utility>

namespace attitude_propagator {

namespace {

// The live parameters, named alike in Parameters and in the reconfigure server's
// AttitudePropagatorConfig (cfg/AttitudePropagator.cfg): one list for both directions.
template <class From, class To>
void copyLiveValues(const From& from, To& to) {
  to.angular_velocity_stddev = from.angular_velocity_stddev;
  to.max_dt = from.max_dt;
  to.torque_timeout = from.torque_timeout;
  to.publish_tf = from.publish_tf;
  to.reverse_tf = from.reverse_tf;
  to.integrator = from.integrator;
}

}  // namespace

Parameters liveParameters(const Parameters& in_force, const AttitudePropagatorConfig& live) {
  Parameters p = in_force;
  copyLiveValues(live, p);
  return p;
}

LiveChange liveChange(const Parameters& now, const Parameters& p) {
  LiveChange change;
  change.engine_changes = p.angular_velocity_stddev != now.angular_velocity_stddev ||
                          p.max_dt != now.max_dt || p.torque_timeout != now.torque_timeout ||
                          p.integrator != now.integrator;
  change.tf_toggled = p.publish_tf != now.publish_tf;
  change.child_changed = p.reverse_tf != now.reverse_tf;
  return change;
}

std::string applyLive(const Parameters& p, const LiveChange& change, AttitudeEngine& engine,
                      NodeConfig& config) {
  std::string error;
  try {
    NodeConfig next = validateParameters(p);
    if (change.engine_changes) error = engine.reconfigure(engineConfig(next));
    if (error.empty()) config = std::move(next);
  } catch (const std::invalid_argument& e) {
    error = e.what();
  }
  return error;
}

std::optional<LogLine> reconfigureText(const std::string& error, bool engine_changes,
                                       const Parameters& in_force, Integrator integrator) {
  if (!error.empty()) {
    // The text quotes the value asked for (the integrator name is any string a client sends).
    return LogLine{ros::console::levels::Warn, "",
                   formatted("reconfigure refused: %s; keeping the values in force",
                             logText(error, 4 * kLogTextBytes).c_str())};
  }
  if (!engine_changes) return std::nullopt;
  return LogLine{
      ros::console::levels::Info, "",
      formatted("reconfigured: integrator %s, max_dt %g s, torque_timeout %g s, "
                "angular_velocity_stddev %g rad/s (the propagator goes on from the current state)",
                integratorName(integrator).c_str(), in_force.max_dt, in_force.torque_timeout,
                in_force.angular_velocity_stddev)};
}

void showInForce(const Parameters& in_force, AttitudePropagatorConfig& live) {
  copyLiveValues(in_force, live);
}

}  // namespace attitude_propagator
