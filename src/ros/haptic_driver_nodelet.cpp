// Nodelet wrapper of rc::HapticDriver (the force loop runs on its own thread inside the manager).
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include <memory>

#include "relaxed_connectivity/ros/haptic_driver.h"

namespace rc {

class HapticDriverNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      driver_ = std::make_unique<HapticDriver>(getNodeHandle(), getPrivateNodeHandle());
    } catch (const std::exception& e) {
      NODELET_FATAL_STREAM("haptic_driver nodelet: " << e.what());
      throw;
    }
  }
  std::unique_ptr<HapticDriver> driver_;
};

}  // namespace rc

PLUGINLIB_EXPORT_CLASS(rc::HapticDriverNodelet, nodelet::Nodelet)
