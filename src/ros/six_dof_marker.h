// The 6-DOF handle of an rviz interactive marker (move and rotate about each axis, drag freely), shared by
// the haptic_driver's stylus marker and object_mover's frame marker.
#pragma once

#include <visualization_msgs/InteractiveMarker.h>

namespace rc {

/// An opaque (or `a`) marker colour.
std_msgs::ColorRGBA markerColor(float r, float g, float b, float a = 1.0f);

/// Appends a free-drag control showing `body` (always visible) and the six axis controls to `marker`.
void addSixDofControls(const visualization_msgs::Marker& body, visualization_msgs::InteractiveMarker* marker);

}  // namespace rc
