// Nodelet wrapper of rc::PaintModel (zero-copy object clouds when run in a nodelet manager with the scanner
// pipeline or the renderer).
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include <memory>

#include "relaxed_connectivity/ros/paint_model.h"

namespace rc {

class PaintModelNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      model_ = std::make_unique<PaintModel>(getNodeHandle(), getPrivateNodeHandle());
    } catch (const std::exception& e) {
      NODELET_FATAL_STREAM("paint_model nodelet: " << e.what());
      throw;
    }
  }
  std::unique_ptr<PaintModel> model_;
};

}  // namespace rc

PLUGINLIB_EXPORT_CLASS(rc::PaintModelNodelet, nodelet::Nodelet)
