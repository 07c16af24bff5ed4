#include "relaxed_connectivity/ros/paint_model.h"

#include <algorithm>

#include <relaxed_connectivity/PaintDelta.h>
#include <relaxed_connectivity/PaintStats.h>
#include <tf2_eigen/tf2_eigen.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string_view>

#include "relaxed_connectivity/core/heap_retention.h"
#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/paint/brush_preset_reader.h"
#include "relaxed_connectivity/paint/paint_type_reader.h"
#include "relaxed_connectivity/paint/painted_surface_io.h"
#include "relaxed_connectivity/ros/brush_messages.h"
#include "relaxed_connectivity/ros/paint_settings.h"
#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace rc {

void PaintModelParams::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("paint_model: " + what); };
  if (brush.empty()) fail("the parameter ~brush (a brush preset file, config/paint/brushes/) is required");
  if (device.empty()) fail("device must not be empty");
  if (world_frame.empty() || world_frame[0] == '/')
    fail("world_frame '" + world_frame + "' is not a frame name");
  if (!(rate > 0) || !std::isfinite(rate)) fail("rate must be positive (got " + std::to_string(rate) + ")");
  try {
    brush_options.validate();
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
  if (!(skin_rate >= 0) || !std::isfinite(skin_rate)) fail("skin_rate must be >= 0");
  if (!(painted_rate > 0) || !std::isfinite(painted_rate)) fail("painted_rate must be positive");
  if (drying_visits < 0) fail("drying_visits must be >= 0");
  if (downsampling_visits < 0) fail("downsampling_visits must be >= 0");
  if (diffusion_surfels < 0) fail("diffusion_surfels must be >= 0");
  if (!(stroke_gap >= 0) || !std::isfinite(stroke_gap)) fail("stroke_gap must be >= 0");
  if (journal_bytes < 0) fail("journal_bytes must be >= 0");
  if (!(autosave_period > 0) || !std::isfinite(autosave_period)) fail("autosave_period must be positive");
  if (!(tf_wait > 0) || !std::isfinite(tf_wait)) fail("tf_wait must be positive");
  if (resume && autosave.empty()) fail("resume needs an autosave file");
  if (!(stats_period > 0) || !std::isfinite(stats_period)) fail("stats_period must be positive");
  try {
    transfer.validate();
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
}

PaintModelParams readPaintModelParams(const ros::NodeHandle& pnh) {
  PaintModelParams p;
  pnh.param("brush", p.brush, p.brush);
  pnh.param("device", p.device, p.device);
  pnh.param("world_frame", p.world_frame, p.world_frame);
  pnh.param("rate", p.rate, p.rate);
  pnh.param("collision_passes", p.brush_options.collision_passes, p.brush_options.collision_passes);
  pnh.param("plane_proxy", p.brush_options.plane_proxy, p.brush_options.plane_proxy);
  pnh.param("proxy_reach", p.brush_options.proxy_reach, p.brush_options.proxy_reach);
  pnh.param("skin_rate", p.skin_rate, p.skin_rate);
  pnh.param("paint", p.paint, p.paint);
  pnh.param("pixel_size", p.transfer.pixel_size, p.transfer.pixel_size);
  pnh.param("pressure_per_depth", p.transfer.pressure_per_depth, p.transfer.pressure_per_depth);
  pnh.param("painted_rate", p.painted_rate, p.painted_rate);
  pnh.param("drying_visits", p.drying_visits, p.drying_visits);
  pnh.param("downsampling_visits", p.downsampling_visits, p.downsampling_visits);
  pnh.param("diffusion_surfels", p.diffusion_surfels, p.diffusion_surfels);
  pnh.param("stroke_gap", p.stroke_gap, p.stroke_gap);
  pnh.param("journal_bytes", p.journal_bytes, p.journal_bytes);
  pnh.param("restore", p.restore, p.restore);
  pnh.param("autosave", p.autosave, p.autosave);
  pnh.param("autosave_period", p.autosave_period, p.autosave_period);
  pnh.param("resume", p.resume, p.resume);
  pnh.param("tf_wait", p.tf_wait, p.tf_wait);
  pnh.param("replace_painted", p.replace_painted, p.replace_painted);
  pnh.param("stats_period", p.stats_period, p.stats_period);
  pnh.param("palette", p.palette, p.palette);
  pnh.param("object", p.object, p.object);
  p.validate();
  return p;
}

PaintModel::PaintModel(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh),
      private_nh_(private_nh),
      params_(readPaintModelParams(private_nh)),
      tf_listener_(tf_buffer_, nh),
      diagnostics_(nh, private_nh, "paint_model") {
  diagnostics_.addInput("surfels", 0.0);  // the object comes once (latched)
  brush_ = std::make_unique<Brush>(readBrushPreset(params_.brush), params_.brush_options);
  contact_pub_ = nh_.advertise<relaxed_connectivity::BrushContact>("brush_contact", 10);
  skeleton_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("brush/skeleton", 2);
  skin_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("brush/skin", 2);
  painted_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("surfels/painted", 1, true);
  delta_pub_ = nh_.advertise<relaxed_connectivity::PaintDelta>("surfels/painted_delta", 100);
  stats_pub_ = nh_.advertise<relaxed_connectivity::PaintStats>("paint_stats", 2);
  start_ = last_autosave_ = last_stats_ = ros::WallTime::now();  // (the dryer's clock starts here)
  if (!params_.paint.empty()) setPaintType(std::make_unique<PaintType>(readPaintType(params_.paint)));
  if (!params_.palette.empty()) palette_ = std::make_unique<PaletteSpec>(readPalette(params_.palette));
  if (params_.resume && std::filesystem::exists(params_.autosave)) {  // restarted: go on from the autosave
    std::lock_guard<std::mutex> lock(model_mutex_);
    installSurface(loadPaintedSurface(params_.autosave), "resumed from the autosave " + params_.autosave);
  } else if (!params_.restore.empty()) {
    std::lock_guard<std::mutex> lock(model_mutex_);
    installSurface(loadPaintedSurface(params_.restore), "restored from " + params_.restore);
  } else if (!params_.object.empty()) {  // an object file instead of the topic (a file error is fatal)
    SurfelCloud cloud = readCloud(params_.object);
    const size_t dropped = cloud.removeNonFinite();
    if (!cloud.hasNormals())
      throw std::invalid_argument("paint_model: ~object " + params_.object +
                                  " has no normals (estimate them with rc_surface or surfel_estimator)");
    if (palette_) appendPalette(cloud, *palette_);
    std::lock_guard<std::mutex> lock(model_mutex_);
    dropped_surfels_ += dropped;
    installSurface(
        std::make_unique<PaintSurface>(std::move(cloud)),
        "from " + params_.object + (dropped ? " (" + std::to_string(dropped) + " non-finite dropped)" : ""));
  }
  // The object waits for the transform of its stamp in a message filter (no lookup blocks the callback), at
  // most tf_wait seconds. An object stamped before the transforms kept (e.g. a latched scan older than the
  // object's frame) is placed with the latest transform, as a static object is; without any, it is refused.
  surfels_input_ = std::make_unique<BoundedTfFilter>(
      nh_, "surfels", 1, tf_buffer_, params_.world_frame, 5, params_.tf_wait,
      [this](const sensor_msgs::PointCloud2ConstPtr& msg) { surfelsCallback(msg, msg->header.stamp); },
      [this](const sensor_msgs::PointCloud2ConstPtr& msg,
             tf2_ros::filter_failure_reasons::FilterFailureReason) {
        if (!msg->header.frame_id.empty() &&
            tf_buffer_.canTransform(params_.world_frame, msg->header.frame_id, ros::Time(0))) {
          ROS_WARN_STREAM("paint_model: surfels (frame '"
                          << msg->header.frame_id << "') older than the transforms to '"
                          << params_.world_frame << "': placed with the latest one");
          return surfelsCallback(msg, ros::Time(0));
        }
        refuseSurfels("no transform of frame '" + msg->header.frame_id + "' to '" + params_.world_frame +
                      "' (tf2_ros::MessageFilter)");
      },
      [this](const sensor_msgs::PointCloud2ConstPtr&, const std::string& reason) { refuseSurfels(reason); });
  pose_sub_ = nh_.subscribe(params_.device + "/pose", 10, &PaintModel::poseCallback, this,
                            ros::TransportHints().tcpNoDelay());
  diagnostics_.addInput(pose_sub_.getTopic(), 2.0);
  services_.push_back(private_nh_.advertiseService("undo", &PaintModel::undo, this));
  services_.push_back(private_nh_.advertiseService("redo", &PaintModel::redo, this));
  services_.push_back(private_nh_.advertiseService("clear", &PaintModel::clear, this));
  services_.push_back(private_nh_.advertiseService("save", &PaintModel::save, this));
  services_.push_back(private_nh_.advertiseService("load", &PaintModel::load, this));
  services_.push_back(private_nh_.advertiseService("set_paint", &PaintModel::setPaint, this));
  services_.push_back(private_nh_.advertiseService("set_brush", &PaintModel::setBrush, this));
  load_action_ =
      std::make_unique<actionlib::SimpleActionServer<relaxed_connectivity::LoadPaintedStateAction>>(
          private_nh_, "load_state", [this](const auto& goal) { loadState(goal); }, false);
  load_action_->start();
  reconfigure_server_ = std::make_unique<dynamic_reconfigure::Server<relaxed_connectivity::PaintConfig>>(
      reconfigure_mutex_, private_nh_);
  publishSettings();  // before the callback: its first call then sees the files' settings, not the defaults
  reconfigure_server_->setCallback(
      [this](relaxed_connectivity::PaintConfig& config, uint32_t level) { reconfigure(config, level); });
  timer_ = nh_.createWallTimer(ros::WallDuration(1.0 / params_.rate), &PaintModel::tick, this);
  ROS_INFO_STREAM("paint_model: brush '"
                  << brush_->preset().name << "' (" << brush_->skeleton().handleCount() << " handle points, "
                  << brush_->skeleton().activeCount() << " active masses, " << brush_->skin().size()
                  << " skin surfels), " << params_.rate << " Hz main loop, device poses on "
                  << pose_sub_.getTopic()
                  << (paint_type_ ? ", paint '" + paint_type_->name + "'" : ", no paint"));
}

PaintModel::~PaintModel() {
  timer_.stop();
  if (load_action_) load_action_->shutdown();
  std::lock_guard<std::mutex> lock(model_mutex_);
  journal_.reset();  // before the surface it observes
}

void PaintModel::setPaintType(std::unique_ptr<PaintType> paint) {
  const double pixel = paintBufferPixel(params_.transfer, brush_->preset());
  if (imprintAliases(*paint, pixel))
    ROS_WARN_STREAM("paint_model: paint '" << paint->name << "': imprint spacing " << paint->imprint_spacing
                                           << " m is below two paint buffer pixels (" << 2 * pixel
                                           << " m): no imprints (lower ~pixel_size to get them)");
  paint_type_ = std::move(paint);
  loadBrush(brush_->skin(), *paint_type_);
  restartBackgroundWork();
}

void PaintModel::restartBackgroundWork() {
  diffusion_.reset();
  dryer_.reset();
  if (!paint_type_) return;
  if (params_.diffusion_surfels > 0 && paint_type_->diffusion > 0) {  // (5.14) only for paint that diffuses
    SurfaceDiffusionOptions o;
    o.max_surfels = size_t(params_.diffusion_surfels);
    diffusion_ = std::make_unique<SurfaceDiffusion>(paint_type_->diffusion, o);
  }
  if (params_.drying_visits > 0 && paint_type_->drying_rate > 0)
    dryer_ = std::make_unique<PaintDryer>(paint_type_->drying_rate, paint_type_->drying,
                                          (ros::WallTime::now() - start_).toSec());
}

bool PaintModel::painted() const {
  return surface_ && (surface_->childCount() > 0 || (journal_ && journal_->undoCount() > 0));
}

void PaintModel::installSurface(std::unique_ptr<PaintSurface> surface, const std::string& what) {
  journal_.reset();
  surface_ = std::move(surface);
  object_hash_ = 0;  // (set by surfelsCallback for an object from the topic)
  object_frame_.clear();
  journal_ = std::make_unique<PaintJournal>(*surface_, size_t(params_.journal_bytes));
  restartBackgroundWork();  // fresh cursors and clocks for the new object
  downsampler_ = params_.downsampling_visits > 0 ? std::make_unique<PaintDownsampler>() : nullptr;
  surface_->takeChangedOriginals();  // the full cloud carries this state
  publish_now_ = true;
  ++object_generation_;
  new_object_ = true;  // its first full cloud goes out with the next tick's stamp
  ROS_INFO_STREAM("paint_model: object of " << surface_->originalCount() << " surfels ("
                                            << surface_->childCount() << " children), " << what);
}

void PaintModel::refuseSurfels(const std::string& reason) {
  ++rejected_;
  diagnostics_.rejected("surfels", reason);
  ROS_ERROR_STREAM("paint_model: rejected surfels: " << reason << "; the current object stays");
}

void PaintModel::surfelsCallback(const sensor_msgs::PointCloud2ConstPtr& msg, ros::Time tf_time) {
  // The same object again (a latched topic re-sent, a reconnect): nothing to do. The same bytes under another
  // layout are another message (and are checked).
  std::string layout = std::to_string(msg->width) + " " + std::to_string(msg->height) + " " +
                       std::to_string(msg->point_step) + " " + std::to_string(msg->row_step) +
                       (msg->is_bigendian ? " big" : " little");
  for (const auto& f : msg->fields)
    layout += " " + f.name + ":" + std::to_string(f.offset) + ":" + std::to_string(f.datatype) + ":" +
              std::to_string(f.count);
  const size_t hash = std::hash<std::string_view>()(std::string_view(
                          reinterpret_cast<const char*>(msg->data.data()), msg->data.size())) ^
                      (std::hash<std::string>()(layout) * 0x9e3779b97f4a7c15ULL);
  {
    std::lock_guard<std::mutex> lock(model_mutex_);
    if (surface_ && hash == object_hash_ && msg->header.frame_id == object_frame_) return;
    if (surface_ && object_hash_ != 0 && !msg->header.stamp.isZero() &&
        msg->header.stamp < object_cloud_stamp_) {  // older than the current object: out of order
      // (a message filter's late failure, placed with the latest transform, of a cloud already superseded:
      // benign, not counted)
      if (tf_time.isZero()) return;
      refuseSurfels("stamp " + std::to_string(msg->header.stamp.toSec()) +
                    " older than the current object's " + std::to_string(object_cloud_stamp_.toSec()));
      return;
    }
  }
  try {
    SurfelCloud cloud = PointCloud2Converter::fromMessage(*msg);
    const size_t dropped = cloud.removeNonFinite();
    if (cloud.empty())
      throw std::invalid_argument(dropped ? "no finite surfel (" + std::to_string(dropped) + " non-finite)"
                                          : std::string("the cloud has no points"));
    if (!cloud.hasNormals())
      throw std::invalid_argument("the cloud has no normals (normal_x/y/z): run it through surfel_estimator");
    if (msg->header.frame_id != params_.world_frame) {
      const auto tf = tf_buffer_.lookupTransform(params_.world_frame, msg->header.frame_id, tf_time);
      cloud.transform(tf2::transformToEigen(tf));
    }
    cloud.frame_id = params_.world_frame;
    const size_t object_size = cloud.size();
    if (palette_) appendPalette(cloud, *palette_);  // (Fig. 5.1) beside the object, in world_frame
    {
      std::lock_guard<std::mutex> lock(model_mutex_);
      if (painted() && !params_.replace_painted)
        throw std::runtime_error(
            "the current object holds paint: call ~clear (or ~save it) first, or set "
            "~replace_painted");
    }
    auto surface = std::make_unique<PaintSurface>(std::move(cloud));  // the kd-tree, outside the lock
    std::lock_guard<std::mutex> lock(model_mutex_);
    if (painted() && !params_.replace_painted)
      throw std::runtime_error("the current object was painted meanwhile");
    const std::string what =
        "from " + surfels_input_->topic() +
        (dropped ? " (" + std::to_string(dropped) + " non-finite dropped)" : "") +
        (palette_ ? ", with the palette '" + palette_->name + "' (" +
                        std::to_string(surface->originalCount() - object_size) + " surfels)"
                  : "");
    installSurface(std::move(surface), what);
    diagnostics_.accepted("surfels");
    object_hash_ = hash;
    object_cloud_stamp_ = msg->header.stamp;
    object_frame_ = msg->header.frame_id;
    dropped_surfels_ += dropped;
  } catch (const std::exception& e) {  // keep the current object
    ++rejected_;
    diagnostics_.rejected("surfels", e.what());
    ROS_ERROR_STREAM("paint_model: rejected surfels (frame '" << msg->header.frame_id << "', "
                                                              << msg->width * msg->height
                                                              << " points): " << e.what());
  }
}

void PaintModel::poseCallback(const geometry_msgs::PoseStampedConstPtr& msg) {
  const auto& p = msg->pose;
  const double q_norm = std::sqrt(p.orientation.x * p.orientation.x + p.orientation.y * p.orientation.y +
                                  p.orientation.z * p.orientation.z + p.orientation.w * p.orientation.w);
  if (!std::isfinite(p.position.x) || !std::isfinite(p.position.y) || !std::isfinite(p.position.z) ||
      !std::isfinite(q_norm) || std::abs(q_norm - 1) > 1e-3) {
    ++rejected_;
    diagnostics_.rejected(pose_sub_.getTopic(), "a non-finite position or a non-unit quaternion");
    ROS_WARN_STREAM_THROTTLE(1.0,
                             "paint_model: dropped a device pose with a non-finite position or a non-unit "
                             "quaternion (|q| = "
                                 << q_norm << ")");
    return;
  }
  diagnostics_.accepted(pose_sub_.getTopic());
  std::lock_guard<std::mutex> lock(input_mutex_);
  latest_pose_ = msg;
}

void PaintModel::tick(const ros::WallTimerEvent&) {
  geometry_msgs::PoseStampedConstPtr pose;
  {
    std::lock_guard<std::mutex> lock(input_mutex_);
    pose = latest_pose_;
  }
  std::lock_guard<std::mutex> lock(model_mutex_);
  ++ticks_;
  const ros::WallTime wall = ros::WallTime::now();
  const ros::Time now = ros::Time::now();
  if (pose) {
    // The device pose in the world (a static tf world -> haptic_base in a session).
    Eigen::Isometry3d world_T_pose_frame = Eigen::Isometry3d::Identity();
    bool have_pose = true;
    if (pose->header.frame_id != params_.world_frame) {
      try {
        world_T_pose_frame = tf2::transformToEigen(
            tf_buffer_.lookupTransform(params_.world_frame, pose->header.frame_id, ros::Time(0)));
      } catch (const tf2::TransformException& e) {
        ROS_WARN_STREAM_THROTTLE(2.0, "paint_model: no transform " << params_.world_frame << " -> "
                                                                   << pose->header.frame_id << ": "
                                                                   << e.what());
        have_pose = false;
      }
    }
    if (have_pose) {
      Eigen::Isometry3d pose_frame_T_stylus;
      tf2::fromMsg(pose->pose, pose_frame_T_stylus);
      const Eigen::Isometry3d world_T_stylus = world_T_pose_frame * pose_frame_T_stylus;
      pose_stamp_ = pose->header.stamp;
      const double dt = 1.0 / params_.rate;
      try {
        if (!brush_placed_) {
          brush_->reset(world_T_stylus);
          brush_placed_ = true;
        }
        brush_->advance(dt, world_T_stylus, surface_.get());
      } catch (const BrushInstability& e) {  // reported, then the brush restarts at rest at the device pose
        ++instabilities_;
        ROS_ERROR_STREAM("paint_model: " << e.what() << "; the brush restarts at rest (" << instabilities_
                                         << " so far)");
        brush_->reset(world_T_stylus);
      }
      const ros::WallTime brushed = ros::WallTime::now();
      brush_s_ += (brushed - wall).toSec();
      if (paint_type_ && surface_) {
        try {
          journal_->beginStroke();  // (no-op while one is open)
          PaintEventStats painted;
          {
            const PaintJournal::Recording recording(*journal_);
            painted = transferPaint(*brush_, *surface_, *paint_type_, dt, params_.transfer);
          }
          if (painted.penetrated_pixels > 0) {
            ++events_;
            idle_ticks_ = 0;
            painted_dirty_ = true;
          } else if (++idle_ticks_ >= std::max(1.0, params_.stroke_gap * params_.rate)) {
            journal_->endStroke();
          }
        } catch (const std::exception& e) {  // the event's paint is lost, the session goes on
          ROS_ERROR_STREAM_THROTTLE(1.0, "paint_model: paint transfer failed: " << e.what());
        }
      }
      transfer_s_ += (ros::WallTime::now() - brushed).toSec();
      contact_pub_.publish(toBrushContactMessage(*brush_, world_T_pose_frame.inverse(), pose->header.frame_id,
                                                 pose->header.stamp));
    }
  }
  const ros::WallTime background = ros::WallTime::now();
  if (surface_ && dryer_)  // (5.6.1) in bounded slices; what dries changes what is seen
    painted_dirty_ =
        dryer_->run(*surface_, (background - start_).toSec(), size_t(params_.drying_visits)) > 0 ||
        painted_dirty_;
  if (surface_ && diffusion_)  // (5.6.2) whole time steps of simulated time, a bounded region each
    painted_dirty_ = diffusion_->run(*surface_, 1.0 / params_.rate).sweeps > 0 || painted_dirty_;
  if (surface_ && downsampler_ && !journal_->strokeOpen())  // (5.5.2), between strokes
    painted_dirty_ =
        downsampler_->run(*surface_, size_t(params_.downsampling_visits)).merged > 0 || painted_dirty_;
  const ros::WallTime published = ros::WallTime::now();
  background_s_ += (published - background).toSec();

  if (skeleton_pub_.getNumSubscribers() > 0)
    skeleton_pub_.publish(toSkeletonMarkers(*brush_, params_.world_frame, now));
  if (params_.skin_rate > 0 && skin_pub_.getNumSubscribers() > 0 &&
      (wall - last_skin_).toSec() >= 1.0 / params_.skin_rate) {
    SurfelCloud skin = brush_->skin().cloud();
    skin.frame_id = params_.world_frame;
    skin.stamp_ns = now.toNSec();
    skin_pub_.publish(PointCloud2Converter::toMessage(skin));
    last_skin_ = wall;
  }
  if (surface_) {
    if (new_object_) object_stamp_ = now, new_object_ = false;
    publishDelta(now);
    if (publish_now_ || (painted_dirty_ && (wall - last_painted_).toSec() >= 1.0 / params_.painted_rate)) {
      publishPainted(now);
      last_painted_ = wall;
    }
    if (!params_.autosave.empty() && (wall - last_autosave_).toSec() >= params_.autosave_period &&
        !journal_->strokeOpen())
      autosave(wall);
  }
  publish_s_ += (ros::WallTime::now() - published).toSec();
  if ((wall - last_stats_).toSec() >= params_.stats_period) publishStats(wall);
}

void PaintModel::publishDelta(const ros::Time& stamp) {
  std::vector<uint32_t> changed = surface_->takeChangedOriginals();
  if (changed.empty()) return;
  if (delta_pub_.getNumSubscribers() == 0) return;  // (the next full cloud carries the change)
  relaxed_connectivity::PaintDelta delta;
  delta.header.stamp = stamp;
  delta.header.frame_id = params_.world_frame;
  delta.sequence = ++delta_sequence_;
  delta.pose_stamp = pose_stamp_;
  delta.object_generation = object_generation_;
  delta.object_stamp = object_stamp_;
  SurfelCloud surfels = surface_->activeCloudOf(changed, /*paint_columns=*/false);  // (a viewer's channels)
  surfels.frame_id = params_.world_frame;
  surfels.stamp_ns = stamp.toNSec();
  PointCloud2Converter::toMessage(surfels, delta.surfels);
  delta.originals = std::move(changed);
  delta_pub_.publish(delta);
}

void PaintModel::publishPainted(const ros::Time& stamp) {
  SurfelCloud painted = surface_->activeCloud();
  painted.frame_id = params_.world_frame;
  painted.stamp_ns = stamp.toNSec();
  painted_pub_.publish(PointCloud2Converter::toMessage(painted));
  painted_dirty_ = publish_now_ = false;
}

void PaintModel::autosave(const ros::WallTime& now) {
  last_autosave_ = now;
  try {
    savePaintedSurface(params_.autosave, *surface_, true);
  } catch (const std::exception& e) {
    ROS_ERROR_STREAM_THROTTLE(60.0, "paint_model: autosave failed: " << e.what());
  }
}

void PaintModel::publishStats(const ros::WallTime& now) {
  const double period = (now - last_stats_).toSec();
  relaxed_connectivity::PaintStats s;
  s.header.stamp = ros::Time::now();
  s.brush = brush_->preset().name;
  s.paint = paint_type_ ? paint_type_->name : "";
  s.events_per_second = events_ / period;
  if (surface_) {
    s.originals = uint32_t(surface_->originalCount());
    s.children = uint32_t(surface_->childCount());
    s.active_surfels = uint32_t(surface_->activeCount());
    const PaintSurface& view = *surface_;
    for (size_t i = 0; i < view.originalCount(); ++i) {
      s.wet_surfels += view.enabled(i) && view.originalPaint(i).wet_volume > 0;
      for (const ChildSurfel& c : view.children(i)) s.wet_surfels += c.paint.wet_volume > 0;
    }
    s.undo_strokes = uint32_t(journal_->undoCount());
    s.redo_strokes = uint32_t(journal_->redoCount());
    s.journal_bytes = journal_->bytes();
  }
  const HeapUsage heap = heapUsage();
  s.heap_in_use_bytes = heap.in_use;
  s.heap_free_bytes = heap.free_held;
  const double per_tick = ticks_ > 0 ? 1e3 / double(ticks_) : 0.0;
  s.brush_ms = brush_s_ * per_tick;
  s.transfer_ms = transfer_s_ * per_tick;
  s.background_ms = background_s_ * per_tick;
  s.publish_ms = publish_s_ * per_tick;
  s.rejected_messages = uint32_t(rejected_);
  s.dropped_surfels = uint32_t(dropped_surfels_);
  s.instabilities = uint32_t(instabilities_);
  stats_pub_.publish(s);
  events_ = ticks_ = 0;
  brush_s_ = transfer_s_ = background_s_ = publish_s_ = 0;
  last_stats_ = now;
}

namespace {

template <class Response>
bool answer(Response& res, bool success, const std::string& message) {
  res.success = success;
  res.message = message;
  if (success)
    ROS_INFO_STREAM("paint_model: " << message);
  else
    ROS_WARN_STREAM("paint_model: " << message);
  return true;
}

}  // namespace

bool PaintModel::undo(Command::Request&, Command::Response& res) {
  std::lock_guard<std::mutex> lock(model_mutex_);
  if (!surface_ || !journal_->undo()) return answer(res, false, "undo: nothing to undo");
  publish_now_ = true;
  return answer(res, true,
                "undo: " + std::to_string(journal_->undoCount()) + " more to undo, " +
                    std::to_string(journal_->redoCount()) + " to redo");
}

bool PaintModel::redo(Command::Request&, Command::Response& res) {
  std::lock_guard<std::mutex> lock(model_mutex_);
  if (!surface_ || !journal_->redo()) return answer(res, false, "redo: nothing to redo");
  publish_now_ = true;
  return answer(res, true, "redo: " + std::to_string(journal_->redoCount()) + " more to redo");
}

bool PaintModel::clear(Command::Request&, Command::Response& res) {
  std::lock_guard<std::mutex> lock(model_mutex_);
  if (!surface_) return answer(res, false, "clear: no object yet");
  journal_->clear();
  surface_->reset();
  publish_now_ = true;
  return answer(res, true,
                "clear: the object as loaded (" + std::to_string(surface_->originalCount()) +
                    " surfels), the journal emptied");
}

bool PaintModel::save(File::Request& req, File::Response& res) {
  std::lock_guard<std::mutex> lock(model_mutex_);
  if (!surface_) return answer(res, false, "save: no object yet");
  try {
    savePaintedSurface(req.path, *surface_, true);
  } catch (const std::exception& e) {
    return answer(res, false, std::string("save: ") + e.what());
  }
  return answer(res, true,
                "save: " + std::to_string(surface_->activeCount()) + " active surfels (" +
                    std::to_string(surface_->childCount()) + " children) to " + req.path);
}

bool PaintModel::loadFrom(const std::string& path, const LoadProgress& progress, std::string* message,
                          size_t* active_surfels) {
  std::unique_ptr<PaintSurface> loaded;
  try {
    loaded = loadPaintedSurface(path, progress);  // outside the lock: painting goes on meanwhile
  } catch (const std::exception& e) {
    ++rejected_;
    *message = std::string("load: ") + e.what();
    return false;
  }
  std::lock_guard<std::mutex> lock(model_mutex_);
  installSurface(std::move(loaded), "loaded from " + path);
  if (active_surfels) *active_surfels = surface_->activeCount();
  *message = "load: " + std::to_string(surface_->activeCount()) + " active surfels from " + path;
  return true;
}

bool PaintModel::load(File::Request& req, File::Response& res) {
  std::string message;
  const bool ok = loadFrom(req.path, {}, &message);
  return answer(res, ok, message);
}

void PaintModel::loadState(const relaxed_connectivity::LoadPaintedStateGoalConstPtr& goal) {
  std::string message;
  size_t active_surfels = 0;
  const bool ok = loadFrom(
      goal->path,
      [&](double fraction, const std::string& stage) {
        relaxed_connectivity::LoadPaintedStateFeedback feedback;
        feedback.progress = float(fraction);
        feedback.stage = stage;
        load_action_->publishFeedback(feedback);
      },
      &message, &active_surfels);
  relaxed_connectivity::LoadPaintedStateResult result;
  result.success = ok;
  result.message = message;
  result.active_surfels = uint32_t(active_surfels);
  if (ok) {
    ROS_INFO_STREAM("paint_model: " << message);
    load_action_->setSucceeded(result, message);
  } else {
    ROS_WARN_STREAM("paint_model: " << message);
    load_action_->setAborted(result, message);
  }
}

bool PaintModel::setPaint(File::Request& req, File::Response& res) {
  try {
    auto paint = std::make_unique<PaintType>(readPaintType(req.path));
    std::string name;
    {
      std::lock_guard<std::mutex> lock(model_mutex_);
      setPaintType(std::move(paint));
      name = paint_type_->name;
    }
    publishSettings();
    return answer(res, true, "set_paint: the brush is loaded with '" + name + "'");
  } catch (const std::exception& e) {
    ++rejected_;
    return answer(res, false, std::string("set_paint: ") + e.what());
  }
}

bool PaintModel::setBrush(File::Request& req, File::Response& res) {
  try {
    auto brush = std::make_unique<Brush>(readBrushPreset(req.path), params_.brush_options);
    std::string name;
    {
      std::lock_guard<std::mutex> lock(model_mutex_);
      installBrush(std::move(brush));
      name = brush_->preset().name;
    }
    publishSettings();
    return answer(res, true, "set_brush: '" + name + "'");
  } catch (const std::exception& e) {
    ++rejected_;
    return answer(res, false, std::string("set_brush: ") + e.what());
  }
}

void PaintModel::installBrush(std::unique_ptr<Brush> brush) {
  brush_ = std::move(brush);
  if (paint_type_) setPaintType(std::make_unique<PaintType>(*paint_type_));  // loads the new brush
  brush_placed_ = false;  // the new brush starts at rest at the next pose
  idle_ticks_ = 0;
  if (journal_) journal_->endStroke();
}

void PaintModel::publishSettings() {
  // Without a paint type its settings show the defaults; changes to them wait for a paint (~set_paint).
  relaxed_connectivity::PaintConfig config = relaxed_connectivity::PaintConfig::__getDefault__();
  {
    std::lock_guard<std::mutex> lock(model_mutex_);
    writePaintReconfigure(brush_->preset(), paint_type_.get(), &config);
  }
  reconfigure_server_->updateConfig(config);
}

void PaintModel::reconfigure(relaxed_connectivity::PaintConfig& config, uint32_t) {
  std::string refused;
  {
    std::lock_guard<std::mutex> lock(model_mutex_);
    BrushPreset preset = brush_->preset();
    PaintType paint = paint_type_ ? *paint_type_ : PaintType();
    applyPaintReconfigure(config, &preset, &paint);
    if (!sameBrushSettings(preset, brush_->preset())) {
      refused = brushStepLimitProblem(preset);
      if (refused.empty()) {
        try {
          installBrush(std::make_unique<Brush>(preset, params_.brush_options));
          ROS_INFO_STREAM("paint_model: brush '" << preset.name
                                                 << "' rebuilt with the reconfigured settings");
        } catch (const std::exception& e) {
          refused = e.what();
        }
      }
    }
    if (paint_type_ && !samePaintSettings(paint, *paint_type_)) {
      *paint_type_ = paint;  // the brush keeps the paint it carries; the new rates apply from the next tick
      restartBackgroundWork();
      ROS_INFO_STREAM("paint_model: paint '" << paint.name << "' reconfigured");
    }
    writePaintReconfigure(brush_->preset(), paint_type_.get(), &config);  // answer with what holds
  }
  if (!refused.empty()) {
    ++rejected_;
    ROS_ERROR_STREAM("paint_model: refused brush settings: " << refused << "; the brush stays as it was");
  }
}

}  // namespace rc
