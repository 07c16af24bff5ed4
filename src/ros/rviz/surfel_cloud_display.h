// rviz display "relaxed_connectivity/SurfelCloud": a PointCloud2 of surfels (any layout PointCloud2Converter
// reads: normals, radii or tangent axes, colours, attributes) drawn as oriented discs of their radius,
// coloured by their colour or any scalar field through viridis. Properties: Topic, Color Field,
// Autocompute Range, Min / Max Value, Radius Scale, Default Radius (clouds without radii), Lighting.
// The status shows the discs drawn and the time the last cloud took to build (convert, quads, upload).
#pragma once

#ifndef Q_MOC_RUN
#include <rviz/message_filter_display.h>
#include <sensor_msgs/PointCloud2.h>

#include <memory>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/render/display/disc_quads.h"
#endif

namespace rviz {
class BoolProperty;
class EnumProperty;
class FloatProperty;
}  // namespace rviz

namespace rc {

class DiscRenderable;

class SurfelCloudDisplay : public rviz::MessageFilterDisplay<sensor_msgs::PointCloud2> {
  Q_OBJECT
 public:
  SurfelCloudDisplay();
  ~SurfelCloudDisplay() override;

  /// Discs drawn from the last cloud, and the milliseconds it took (for tests and the bench).
  size_t discs() const;
  double lastBuildMilliseconds() const { return build_ms_; }

 protected:
  void onInitialize() override;
  void reset() override;
  void processMessage(const sensor_msgs::PointCloud2::ConstPtr& msg) override;

 private Q_SLOTS:
  void rebuild();
  void updateMaterial();
  void updateColourFields();

 private:
  DiscQuadOptions options() const;

  rviz::EnumProperty* colour_field_property_;
  rviz::BoolProperty* auto_range_property_;
  rviz::FloatProperty* min_value_property_;
  rviz::FloatProperty* max_value_property_;
  rviz::FloatProperty* radius_scale_property_;
  rviz::FloatProperty* default_radius_property_;
  rviz::BoolProperty* lighting_property_;

  SurfelCloud cloud_;  ///< of the last accepted message, in its frame
  std::vector<DiscVertex> vertices_;
  std::unique_ptr<DiscRenderable> discs_;
  std::string material_name_;
  double build_ms_ = 0;
};

}  // namespace rc
