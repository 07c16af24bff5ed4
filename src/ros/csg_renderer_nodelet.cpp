// Nodelet wrapper of rc::CsgRenderer (zero-copy clouds in, images out, when run in one manager with the
// surfel sources).
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include <memory>

#include "relaxed_connectivity/ros/csg_renderer.h"

namespace rc {

class CsgRendererNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      renderer_ = std::make_unique<CsgRenderer>(getNodeHandle(), getPrivateNodeHandle());
    } catch (const std::exception& e) {
      NODELET_FATAL_STREAM("csg_renderer nodelet: " << e.what());
      throw;
    }
  }
  std::unique_ptr<CsgRenderer> renderer_;
};

}  // namespace rc

PLUGINLIB_EXPORT_CLASS(rc::CsgRendererNodelet, nodelet::Nodelet)
