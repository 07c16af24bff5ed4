// Nodelet wrapper of rc::MeshConverter (the painted object arrives zero-copy when run in the session's
// nodelet manager).
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include <memory>

#include "relaxed_connectivity/ros/mesh_converter.h"

namespace rc {

class MeshConverterNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      converter_ = std::make_unique<MeshConverter>(getNodeHandle(), getPrivateNodeHandle());
    } catch (const std::exception& e) {
      NODELET_FATAL_STREAM("mesh_converter nodelet: " << e.what());
      throw;
    }
  }
  std::unique_ptr<MeshConverter> converter_;
};

}  // namespace rc

PLUGINLIB_EXPORT_CLASS(rc::MeshConverterNodelet, nodelet::Nodelet)
