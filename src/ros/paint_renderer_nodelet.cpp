// Nodelet wrapper of rc::PaintRenderer: in the paint model's manager the painted cloud and the deltas arrive
// without serialisation (zero-copy).
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include <memory>

#include "relaxed_connectivity/ros/paint_renderer.h"

namespace rc {

class PaintRendererNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      renderer_ = std::make_unique<PaintRenderer>(getNodeHandle(), getPrivateNodeHandle());
    } catch (const std::exception& e) {
      NODELET_FATAL_STREAM("paint_renderer nodelet: " << e.what());
      throw;
    }
  }
  std::unique_ptr<PaintRenderer> renderer_;
};

}  // namespace rc

PLUGINLIB_EXPORT_CLASS(rc::PaintRendererNodelet, nodelet::Nodelet)
