#include "relaxed_connectivity/ros/six_dof_marker.h"

#include <string>

namespace rc {
namespace {

visualization_msgs::InteractiveMarkerControl axisControl(const std::string& name, double x, double y,
                                                         double z, uint8_t mode) {
  visualization_msgs::InteractiveMarkerControl c;
  c.name = name;
  c.orientation.w = 1;
  c.orientation.x = x;
  c.orientation.y = y;
  c.orientation.z = z;
  c.interaction_mode = mode;
  return c;
}

}  // namespace

std_msgs::ColorRGBA markerColor(float r, float g, float b, float a) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

void addSixDofControls(const visualization_msgs::Marker& body,
                       visualization_msgs::InteractiveMarker* marker) {
  using Control = visualization_msgs::InteractiveMarkerControl;
  Control grab;
  grab.always_visible = true;
  grab.interaction_mode = Control::MOVE_ROTATE_3D;
  grab.markers.push_back(body);
  marker->controls.push_back(grab);
  marker->controls.push_back(axisControl("rotate_x", 1, 0, 0, Control::ROTATE_AXIS));
  marker->controls.push_back(axisControl("move_x", 1, 0, 0, Control::MOVE_AXIS));
  marker->controls.push_back(axisControl("rotate_z", 0, 1, 0, Control::ROTATE_AXIS));
  marker->controls.push_back(axisControl("move_z", 0, 1, 0, Control::MOVE_AXIS));
  marker->controls.push_back(axisControl("rotate_y", 0, 0, 1, Control::ROTATE_AXIS));
  marker->controls.push_back(axisControl("move_y", 0, 0, 1, Control::MOVE_AXIS));
}

}  // namespace rc
