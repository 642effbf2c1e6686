// attitude_propagator/AttitudePropagatorNodelet: the wrapper inside a nodelet manager, so
// input and output messages pass between nodelets as shared pointers, without a copy.
#include <memory>
#include <stdexcept>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "attitude_propagator/ros/attitude_propagator_ros.h"

namespace attitude_propagator {

class AttitudePropagatorNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      // getNodeHandle(): a single-threaded queue per nodelet, which the wrapper relies on.
      wrapper_ = std::make_unique<AttitudePropagatorRos>(getNodeHandle(), getPrivateNodeHandle());
    } catch (const std::exception& e) {
      NODELET_FATAL("attitude_propagator %s: refusing to start: %s", getName().c_str(), e.what());
      throw;  // the manager then refuses to load the nodelet
    }
  }

  std::unique_ptr<AttitudePropagatorRos> wrapper_;
};

}  // namespace attitude_propagator

PLUGINLIB_EXPORT_CLASS(attitude_propagator::AttitudePropagatorNodelet, nodelet::Nodelet)
