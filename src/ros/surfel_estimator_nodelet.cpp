// Nodelet wrapper of rc::SurfelEstimator (zero-copy clouds when run in a nodelet manager with the scanner).
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include <memory>

#include "relaxed_connectivity/ros/surfel_estimator.h"

namespace rc {

class SurfelEstimatorNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      estimator_ = std::make_unique<SurfelEstimator>(getNodeHandle(), getPrivateNodeHandle());
    } catch (const std::exception& e) {
      NODELET_FATAL_STREAM("surfel_estimator nodelet: " << e.what());
      throw;
    }
  }
  std::unique_ptr<SurfelEstimator> estimator_;
};

}  // namespace rc

PLUGINLIB_EXPORT_CLASS(rc::SurfelEstimatorNodelet, nodelet::Nodelet)
