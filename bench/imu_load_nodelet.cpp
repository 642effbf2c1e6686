// attitude_propagator/ImuLoadGeneratorNodelet: the load generator inside the propagator's
// nodelet manager, so messages pass both ways as shared pointers, without serialisation.
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "imu_load_generator.h"

namespace attitude_propagator_bench {

class ImuLoadGeneratorNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    generator_ = std::make_unique<ImuLoadGenerator>(getNodeHandle(), getPrivateNodeHandle());
  }

  std::unique_ptr<ImuLoadGenerator> generator_;
};

}  // namespace attitude_propagator_bench

PLUGINLIB_EXPORT_CLASS(attitude_propagator_bench::ImuLoadGeneratorNodelet, nodelet::Nodelet)
