#include "relaxed_connectivity/ros/mesh_converter.h"

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include "relaxed_connectivity/convert/textured_mesh_io.h"
#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/ros/point_cloud2_converter.h"
#include "relaxed_connectivity/surface/normal_estimation.h"

namespace rc {
namespace {

/// Typical shares of a conversion's time per stage (the Igea in bench_conversion), for the overall progress.
constexpr double kStageShare[] = {0.25, 0.28, 0.04, 0.38, 0.01};
constexpr double kReadShare = 0.02, kWriteShare = 0.02;

std::string defaultOutputDir() {
  const char* home = std::getenv("ROS_HOME");
  if (home) return std::string(home) + "/converted";
  home = std::getenv("HOME");
  return std::string(home ? home : "/tmp") + "/.ros/converted";
}

}  // namespace

void MeshConverterParams::validate() const {
  auto bad = [](const std::string& what) { throw std::invalid_argument("mesh_converter: " + what); };
  const SimplificationOptions& s = conversion.simplification;
  if (!(s.max_error >= 0) || (s.max_error == 0 && s.target_triangles == 0))
    bad("simplify_error must be >= 0, and simplify_error or target_triangles > 0");
  const TextureOptions& t = conversion.texture;
  if (!(t.color_error >= 0) || !(t.normal_error >= 0) || !(t.depth_error >= 0))
    bad("color_error, normal_error and depth_error must be >= 0");
  if (conversion.atlas.border < 0) bad("border must be >= 0");
  const int p = conversion.atlas.max_page_size;
  if (p < 64 || (p & (p - 1))) bad("max_page_size must be a power of two >= 64, not " + std::to_string(p));
  if (!write_obj && !write_glb) bad("write_obj or write_glb must be true");
}

MeshConverterParams readMeshConverterParams(const ros::NodeHandle& pnh) {
  MeshConverterParams p;
  pnh.param("output_dir", p.output_dir, p.output_dir);
  pnh.param("write_obj", p.write_obj, p.write_obj);
  pnh.param("write_glb", p.write_glb, p.write_glb);
  ConversionOptions& c = p.conversion;
  pnh.param("simplify_error", c.simplification.max_error, c.simplification.max_error);
  int triangles = int(c.simplification.target_triangles);
  pnh.param("target_triangles", triangles, triangles);
  if (triangles < 0) throw std::invalid_argument("mesh_converter: target_triangles must be >= 0");
  c.simplification.target_triangles = size_t(triangles);
  pnh.param("color_error", c.texture.color_error, c.texture.color_error);
  pnh.param("normal_error", c.texture.normal_error, c.texture.normal_error);
  pnh.param("normal_texture", c.texture.normal_texture, c.texture.normal_texture);
  pnh.param("depth_error", c.texture.depth_error, c.texture.depth_error);
  pnh.param("depth_texture", c.texture.depth_texture, c.texture.depth_texture);
  pnh.param("border", c.atlas.border, c.atlas.border);
  pnh.param("max_page_size", c.atlas.max_page_size, c.atlas.max_page_size);
  pnh.param("fill_gaps", c.atlas.fill_gaps, c.atlas.fill_gaps);
  pnh.param("require_manifold", c.reconstruction.require_manifold, c.reconstruction.require_manifold);
  std::string method = reconstructionMethodName(c.reconstruction.method);
  pnh.param("reconstruction", method, method);
  try {
    c.reconstruction.method = reconstructionMethodFromName(method);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("mesh_converter: ~") + e.what());
  }
  std::vector<double> viewpoint;
  pnh.param("viewpoint", viewpoint, viewpoint);
  if (viewpoint.size() == 3) {
    p.viewpoint = Vec3(viewpoint[0], viewpoint[1], viewpoint[2]);
  } else if (!viewpoint.empty()) {
    throw std::invalid_argument("mesh_converter: viewpoint must be [x, y, z] or []");
  }
  if (p.output_dir.empty()) p.output_dir = defaultOutputDir();
  p.validate();
  return p;
}

visualization_msgs::Marker meshMarker(const TexturedMesh& mesh, const std::string& frame_id) {
  visualization_msgs::Marker m;
  m.header.frame_id = frame_id;
  m.header.stamp = ros::Time::now();
  m.ns = "converted";
  m.id = 0;
  m.type = visualization_msgs::Marker::TRIANGLE_LIST;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1;
  m.scale.x = m.scale.y = m.scale.z = 1;
  m.color.a = 1;
  m.points.reserve(3 * mesh.mesh.triangles.size());
  m.colors.reserve(m.points.capacity());
  for (size_t t = 0; t < mesh.mesh.triangles.size(); ++t) {
    const TexturePage& page = mesh.pages[size_t(mesh.page[t])];
    for (int c = 0; c < 3; ++c) {
      const Vec3& p = mesh.mesh.vertices.positions[mesh.mesh.triangles[t][size_t(c)]];
      geometry_msgs::Point point;
      point.x = p.x(), point.y = p.y(), point.z = p.z();
      m.points.push_back(point);
      const Eigen::Vector3f color = samplePage(page.color, page.width, page.height, mesh.uv[t][size_t(c)].x(),
                                               mesh.uv[t][size_t(c)].y());
      std_msgs::ColorRGBA rgba;
      rgba.r = color.x(), rgba.g = color.y(), rgba.b = color.z(), rgba.a = 1;
      m.colors.push_back(rgba);
    }
  }
  return m;
}

MeshConverter::MeshConverter(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh),
      private_nh_(private_nh),
      params_(readMeshConverterParams(private_nh)),
      diagnostics_(nh, private_nh, "mesh_converter") {
  if (!meshGenerationAvailable())
    ROS_WARN("mesh_converter: this build has no CGAL (libcgal-dev): every goal will be aborted");
  surfels_sub_ = nh_.subscribe("surfels", 1, &MeshConverter::surfelsCallback, this);
  diagnostics_.addInput(surfels_sub_.getTopic(), 0.0);  // a latched cloud, converted on request
  diagnostics_.addTask("conversion", [this](diagnostic_updater::DiagnosticStatusWrapper& status) {
    std::lock_guard<std::mutex> lock(mutex_);
    status.add("goals succeeded", goals_succeeded_);
    status.add("goals aborted", goals_aborted_);
    status.add("last abort", last_abort_);
    if (!meshGenerationAvailable())
      status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "this build has no CGAL: every goal aborts");
    else
      status.summaryf(diagnostic_msgs::DiagnosticStatus::OK, "%u goals converted, %u aborted",
                      goals_succeeded_, goals_aborted_);
  });
  marker_pub_ = private_nh_.advertise<visualization_msgs::Marker>("converted", 1, true);
  server_ = std::make_unique<Server>(
      private_nh_, "convert", [this](const auto& goal) { convert(goal); }, false);
  server_->start();
  ROS_INFO_STREAM("mesh_converter: ~convert ready; output to "
                  << params_.output_dir << ", simplification " << params_.conversion.simplification.max_error
                  << " / " << params_.conversion.simplification.target_triangles
                  << " triangles, colour threshold " << params_.conversion.texture.color_error);
}

void MeshConverter::surfelsCallback(const sensor_msgs::PointCloud2ConstPtr& msg) {
  diagnostics_.accepted(surfels_sub_.getTopic());
  std::lock_guard<std::mutex> lock(mutex_);
  latest_ = msg;
}

SurfelCloud MeshConverter::goalSurfels(const relaxed_connectivity::ConvertSurfelsGoal& goal,
                                       std::string* frame_id, std::string* name) {
  const sensor_msgs::PointCloud2* msg = nullptr;
  sensor_msgs::PointCloud2ConstPtr latest;
  // (64-bit: a width * height that wraps to 0 in 32 bits is still a cloud, and is checked)
  if (uint64_t(goal.cloud.width) * goal.cloud.height > 0 || !goal.cloud.data.empty()) {
    msg = &goal.cloud;
  } else if (goal.use_latest) {
    std::lock_guard<std::mutex> lock(mutex_);
    latest = latest_;
    if (!latest)
      throw std::invalid_argument("use_latest: no cloud has arrived on " + surfels_sub_.getTopic() + " yet");
    msg = latest.get();
  }
  if (msg) {
    PointCloud2Converter::checkMessage(*msg);
    *frame_id = msg->header.frame_id;
    *name = msg->header.frame_id.empty() ? "cloud" : msg->header.frame_id;
    SurfelCloud cloud = PointCloud2Converter::fromMessage(*msg);
    if (!cloud.hasNormals())
      throw std::invalid_argument(
          "the cloud has no normal_x/y/z fields (estimate normals first, e.g. surfel_estimator)");
    return cloud;
  }
  if (goal.input_file.empty())
    throw std::invalid_argument("the goal names no cloud, no input_file and not use_latest");
  SurfelCloud cloud = readCloud(goal.input_file);
  cloud.removeNonFinite();
  if (!cloud.hasNormals()) {
    NormalEstimationConfig config;
    config.viewpoint = params_.viewpoint;
    estimateNormals(cloud, config);
  }
  *frame_id = "";
  *name = std::filesystem::path(goal.input_file).stem().string();
  return cloud;
}

void MeshConverter::convert(const relaxed_connectivity::ConvertSurfelsGoalConstPtr& goal) {
  const auto t0 = std::chrono::steady_clock::now();
  relaxed_connectivity::ConvertSurfelsResult result;
  auto feedback = [&](const std::string& stage, double stage_fraction, double overall) {
    relaxed_connectivity::ConvertSurfelsFeedback f;
    f.stage = stage;
    f.stage_progress = float(stage_fraction);
    f.progress = float(overall);
    server_->publishFeedback(f);
  };
  auto abort = [&](const std::string& message) {
    result.success = false;
    result.message = message;
    ROS_WARN_STREAM("mesh_converter: goal aborted: " << message);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++goals_aborted_;
      last_abort_ = message;
    }
    server_->setAborted(result, message);
  };
  try {
    feedback("reading", 0, 0);
    std::string frame_id, name;
    const SurfelCloud surfels = goalSurfels(*goal, &frame_id, &name);
    result.surfels = uint32_t(surfels.size());
    if (server_->isPreemptRequested()) throw ConversionCancelled("reading");
    ConversionOptions options = params_.conversion;
    if (goal->simplify_error > 0 || goal->target_triangles > 0) {
      options.simplification.max_error = goal->simplify_error;
      options.simplification.target_triangles = goal->target_triangles;
    }
    if (goal->color_error > 0) options.texture.color_error = goal->color_error;
    if (goal->normal_error > 0) options.texture.normal_error = goal->normal_error;
    if (!std::isfinite(goal->simplify_error) || goal->simplify_error < 0 ||
        !std::isfinite(goal->color_error) || goal->color_error < 0 || !std::isfinite(goal->normal_error) ||
        goal->normal_error < 0)
      throw std::invalid_argument("the goal's error parameters must be finite and >= 0");
    double done_share = kReadShare;
    int last_stage = -1;
    const ConversionResult r = convertSurfels(surfels, options, [&](ConversionStage stage, double fraction) {
      const int s = int(stage);
      if (s != last_stage) {
        for (int k = std::max(0, last_stage); k < s; ++k) done_share += last_stage < 0 ? 0 : kStageShare[k];
        last_stage = s;
      }
      feedback(stageName(stage), fraction, std::min(1.0, done_share + fraction * kStageShare[s]));
      return !server_->isPreemptRequested() && ros::ok();
    });
    feedback("writing", 0, 1.0 - kWriteShare);
    const bool obj = goal->write_obj || (!goal->write_glb && params_.write_obj);
    const bool glb = goal->write_glb || (!goal->write_obj && params_.write_glb);
    std::string prefix = goal->output_prefix;
    if (prefix.empty()) {
      std::string safe = name;
      for (char& c : safe)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
      prefix = params_.output_dir + "/" + safe + "_" + std::to_string(int64_t(ros::WallTime::now().toSec()));
    }
    const std::filesystem::path dir = std::filesystem::path(prefix).parent_path();
    if (!dir.empty()) std::filesystem::create_directories(dir);
    if (obj)
      for (const std::string& f : writeTexturedObj(prefix + ".obj", r.textured)) result.files.push_back(f);
    if (glb) {
      writeGlb(prefix + ".glb", r.textured);
      result.files.push_back(prefix + ".glb");
    }
    result.success = true;
    result.triangles = uint32_t(r.textured.mesh.triangles.size());
    result.texture_pages = uint32_t(r.textured.layout.pages);
    result.page_size = uint32_t(r.textured.layout.page_size);
    result.texture_usage = r.textured.layout.usage;
    result.texture_usage_with_borders = r.textured.layout.usage_with_borders;
    result.hausdorff = r.geometric_error.hausdorff;
    result.rms = r.geometric_error.rms;
    result.color_error_mean = r.color_error_mean;
    result.color_error_max = r.color_error_max;
    result.patches_at_resolution_limit = uint32_t(r.texture.at_resolution_limit);
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    char summary[256];
    std::snprintf(
        summary, sizeof summary,
        "%u surfels -> %u triangles, %u page(s) of %u (usage %.0f %%), Hausdorff %.2e, colour error "
        "%.3f mean, %.1f s",
        result.surfels, result.triangles, result.texture_pages, result.page_size,
        100 * result.texture_usage_with_borders, result.hausdorff, result.color_error_mean, result.seconds);
    result.message = summary;
    marker_pub_.publish(meshMarker(r.textured, frame_id.empty() ? "world" : frame_id));
    feedback("writing", 1, 1);
    ROS_INFO_STREAM("mesh_converter: " << summary << " -> " << prefix);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++goals_succeeded_;
    }
    server_->setSucceeded(result, result.message);
  } catch (const ConversionCancelled& e) {
    result.success = false;
    result.message = e.what();
    ROS_INFO_STREAM("mesh_converter: " << e.what());
    server_->setPreempted(result, result.message);
  } catch (const std::exception& e) {
    abort(e.what());
  }
}

}  // namespace rc
