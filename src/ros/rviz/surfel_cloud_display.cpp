#include "relaxed_connectivity/ros/rviz/surfel_cloud_display.h"

#include <OGRE/OgreMaterialManager.h>
#include <OGRE/OgreResourceGroupManager.h>
#include <OGRE/OgreSceneNode.h>
#include <OGRE/OgreTechnique.h>
#include <rviz/display_context.h>
#include <rviz/frame_manager.h>
#include <rviz/properties/bool_property.h>
#include <rviz/properties/enum_property.h>
#include <rviz/properties/float_property.h>
#include <pluginlib/class_list_macros.hpp>

#include <chrono>

#include "relaxed_connectivity/ros/point_cloud2_converter.h"
#include "relaxed_connectivity/ros/rviz/disc_renderable.h"

namespace rc {

SurfelCloudDisplay::SurfelCloudDisplay() {
  colour_field_property_ = new rviz::EnumProperty(
      "Color Field", "rgb", "The surfels' colours (rgb) or a scalar field through viridis.", this,
      SLOT(rebuild()));
  colour_field_property_->addOption("rgb");
  connect(colour_field_property_, SIGNAL(requestOptions(EnumProperty*)), this, SLOT(updateColourFields()));
  auto_range_property_ = new rviz::BoolProperty(
      "Autocompute Range", true, "Map the field's range over the cloud; else Min Value .. Max Value.", this,
      SLOT(rebuild()));
  min_value_property_ =
      new rviz::FloatProperty("Min Value", 0.0f, "Field value mapped to dark blue.", this, SLOT(rebuild()));
  max_value_property_ =
      new rviz::FloatProperty("Max Value", 1.0f, "Field value mapped to yellow.", this, SLOT(rebuild()));
  radius_scale_property_ = new rviz::FloatProperty("Radius Scale", 1.0f, "Multiplies every surfel's radius.",
                                                   this, SLOT(rebuild()));
  radius_scale_property_->setMin(0.0f);
  default_radius_property_ = new rviz::FloatProperty(
      "Default Radius", 0.005f, "Radius [m] of surfels of clouds without a radius field.", this,
      SLOT(rebuild()));
  default_radius_property_->setMin(0.0f);
  lighting_property_ =
      new rviz::BoolProperty("Lighting", true, "Shade the discs by their normals (else flat colours).", this,
                             SLOT(updateMaterial()));
}

SurfelCloudDisplay::~SurfelCloudDisplay() {
  if (discs_ && scene_node_) scene_node_->detachObject(discs_.get());
  discs_.reset();
  if (!material_name_.empty())
    Ogre::MaterialManager::getSingleton().remove(material_name_, Ogre::RGN_DEFAULT);
}

void SurfelCloudDisplay::onInitialize() {
  MFDClass::onInitialize();
  static int count = 0;
  material_name_ = "relaxed_connectivity_surfel_discs_" + std::to_string(count++);
  discs_ =
      std::make_unique<DiscRenderable>(createDiscMaterial(material_name_, lighting_property_->getBool()));
  scene_node_->attachObject(discs_.get());
}

void SurfelCloudDisplay::reset() {
  MFDClass::reset();
  cloud_ = SurfelCloud();
  vertices_.clear();
  if (discs_) discs_->setVertices(vertices_);
}

size_t SurfelCloudDisplay::discs() const {
  return discs_ ? discs_->discs() : 0;
}

DiscQuadOptions SurfelCloudDisplay::options() const {
  DiscQuadOptions o;
  o.colour_field = colour_field_property_->getStdString();
  o.auto_range = auto_range_property_->getBool();
  o.min_value = min_value_property_->getFloat();
  o.max_value = max_value_property_->getFloat();
  o.radius_scale = radius_scale_property_->getFloat();
  o.default_radius = default_radius_property_->getFloat();
  return o;
}

void SurfelCloudDisplay::processMessage(const sensor_msgs::PointCloud2::ConstPtr& msg) {
  Ogre::Vector3 position;
  Ogre::Quaternion orientation;
  if (!context_->getFrameManager()->getTransform(msg->header, position, orientation)) {
    setStatus(rviz::StatusProperty::Error, "Transform",
              QString::fromStdString("no transform from '" + msg->header.frame_id + "' to '" +
                                     fixed_frame_.toStdString() + "'"));
    return;
  }
  setStatus(rviz::StatusProperty::Ok, "Transform", "ok");
  const auto start = std::chrono::steady_clock::now();
  try {
    SurfelCloud cloud = PointCloud2Converter::fromMessage(*msg);
    if (!cloud.hasNormals() && !cloud.hasAxes())
      throw std::invalid_argument("the cloud has neither normals nor tangent axes (not surfels)");
    cloud_ = std::move(cloud);
  } catch (const std::exception& e) {  // the last good cloud stays
    setStatus(rviz::StatusProperty::Error, "Message", QString::fromStdString(e.what()));
    return;
  }
  setStatus(rviz::StatusProperty::Ok, "Message", "ok");
  scene_node_->setPosition(position);
  scene_node_->setOrientation(orientation);
  rebuild();
  build_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  setStatus(rviz::StatusProperty::Ok, "Discs",
            QString::number(discs()) + " discs, built in " + QString::number(build_ms_, 'f', 1) + " ms");
}

void SurfelCloudDisplay::rebuild() {
  if (!discs_ || cloud_.size() == 0) return;
  DiscQuadOptions o = options();
  const std::vector<std::string> fields = discColourFields(cloud_);
  if (std::find(fields.begin(), fields.end(), o.colour_field) == fields.end()) {
    if (o.colour_field != "rgb")
      setStatus(rviz::StatusProperty::Warn, "Color Field",
                QString::fromStdString("no field '" + o.colour_field + "': colours shown"));
    o.colour_field = cloud_.hasColors() ? "rgb" : "z";
  } else {
    deleteStatus("Color Field");
  }
  try {
    const DiscQuadStats stats = buildDiscQuads(cloud_, o, &vertices_);
    if (o.colour_field != "rgb" && o.auto_range) {
      min_value_property_->setFloat(float(stats.min_value));
      max_value_property_->setFloat(float(stats.max_value));
    }
    if (stats.skipped)
      setStatus(rviz::StatusProperty::Warn, "Skipped",
                QString::number(stats.skipped) + " surfels with non-finite position or normal");
    else
      deleteStatus("Skipped");
  } catch (const std::exception& e) {
    setStatus(rviz::StatusProperty::Error, "Message", QString::fromStdString(e.what()));
    return;
  }
  discs_->setVertices(vertices_);
  context_->queueRender();
}

void SurfelCloudDisplay::updateMaterial() {
  Ogre::MaterialPtr material =
      Ogre::MaterialManager::getSingleton().getByName(material_name_, Ogre::RGN_DEFAULT);
  if (material) material->getTechnique(0)->getPass(0)->setLightingEnabled(lighting_property_->getBool());
  context_->queueRender();
}

void SurfelCloudDisplay::updateColourFields() {
  colour_field_property_->clearOptions();
  if (cloud_.size() == 0) colour_field_property_->addOption("rgb");
  for (const std::string& f : discColourFields(cloud_)) colour_field_property_->addOptionStd(f);
}

}  // namespace rc

PLUGINLIB_EXPORT_CLASS(rc::SurfelCloudDisplay, rviz::Display)
