// The `marker` backend of the haptic_driver: an rviz interactive marker (6-DOF handle) stands for the stylus,
// so a person paints with the mouse. Its right-click menu toggles button 0 (paint). Poses come at mouse rate;
// the force loop holds the latest one (HeldPoseDevice).
#pragma once

#include <interactive_markers/interactive_marker_server.h>
#include <interactive_markers/menu_handler.h>

#include <memory>
#include <string>

#include "relaxed_connectivity/ros/haptic_device.h"

namespace rc {

class MarkerHapticDevice : public HeldPoseDevice {
 public:
  /// Serves the marker on `<topic_ns>/update` etc., in `frame`, starting at `start_position`.
  MarkerHapticDevice(const std::string& topic_ns, const std::string& frame, const Vec3& start_position,
                     double brush_length);
  bool publishesPose() const override { return true; }

 private:
  void feedback(const visualization_msgs::InteractiveMarkerFeedbackConstPtr& feedback);
  void togglePaint(const visualization_msgs::InteractiveMarkerFeedbackConstPtr& feedback);

  std::unique_ptr<interactive_markers::InteractiveMarkerServer> server_;
  interactive_markers::MenuHandler menu_;
  interactive_markers::MenuHandler::EntryHandle paint_entry_ = 0;
  bool painting_ = false;
  ros::Time stamp_origin_;
};

}  // namespace rc
