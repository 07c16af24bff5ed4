// csg_renderer with two sphere patches on patch topics, checked against exact CSG ray casting
// (analytic_csg.h): the tree selects patches, "0 - 1" carves patch 1 into patch 0 at the analytic depth, bad
// expressions and bad clouds are rejected with a reason while the last good state keeps rendering, and
// nothing is re-rendered while nothing changes; a second node with back-face culling refuses differences.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <relaxed_connectivity/CsgRenderStats.h>
#include <relaxed_connectivity/SetCsgTree.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <string>

#include "reconfigure_support.h"
#include "relaxed_connectivity/render/csg/analytic_csg.h"
#include "relaxed_connectivity/render/csg/patch_sampling.h"
#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace {

using relaxed_connectivity::CsgRenderStats;
using sensor_msgs::ImageConstPtr;

constexpr uint32_t kWidth = 160, kHeight = 120;
constexpr double kFovDegrees = 60.0;
const rc::Vec3 kCenterA(0, 0, 0), kCenterB(0, 0, -1);
constexpr double kRadiusA = 1.0, kRadiusB = 0.6;
constexpr size_t kSamplesA = 6000, kSamplesB = 3000;

struct Frame {
  CsgRenderStats stats;
  ImageConstPtr image, depth, patch;
};

float depthAt(const sensor_msgs::Image& depth, uint32_t u, uint32_t v) {
  float d;
  std::memcpy(&d, &depth.data[v * depth.step + 4 * u], 4);
  return d;
}
int32_t patchAt(const sensor_msgs::Image& patch, uint32_t u, uint32_t v) {
  int32_t p;
  std::memcpy(&p, &patch.data[v * patch.step + 4 * u], 4);
  return p;
}

class CsgRendererNode : public ::testing::Test {
 protected:
  void SetUp() override {
    ros::NodeHandle nh;
    image_sub_ = nh.subscribe<sensor_msgs::Image>("csg_renderer/image", 10, [this](const ImageConstPtr& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      images_.push_back(m);
    });
    depth_sub_ = nh.subscribe<sensor_msgs::Image>("csg_renderer/depth", 10, [this](const ImageConstPtr& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      depths_.push_back(m);
    });
    patch_sub_ =
        nh.subscribe<sensor_msgs::Image>("csg_renderer/patch_id", 10, [this](const ImageConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          patches_.push_back(m);
        });
    info_sub_ = nh.subscribe<sensor_msgs::CameraInfo>("csg_renderer/camera_info", 10,
                                                      [this](const sensor_msgs::CameraInfoConstPtr& m) {
                                                        std::lock_guard<std::mutex> lock(mutex_);
                                                        info_ = m;
                                                      });
    stats_sub_ = nh.subscribe<CsgRenderStats>("csg_renderer/stats", 50, [this](const auto& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      stats_.push_back(*m);
    });
    pub_a_ = nh.advertise<sensor_msgs::PointCloud2>("patch_a", 1, true);
    pub_b_ = nh.advertise<sensor_msgs::PointCloud2>("patch_b", 1, true);
    pub_surfels_ = nh.advertise<sensor_msgs::PointCloud2>("surfels", 1, true);
    set_tree_ = nh.serviceClient<relaxed_connectivity::SetCsgTree>("csg_renderer/set_csg_tree");
    ASSERT_TRUE(set_tree_.waitForExistence(ros::Duration(20.0))) << "csg_renderer is not running";
    ASSERT_TRUE(waitFor(
        [&] {
          return pub_a_.getNumSubscribers() > 0 && pub_b_.getNumSubscribers() > 0 &&
                 pub_surfels_.getNumSubscribers() > 0 && stats_sub_.getNumPublishers() > 0 &&
                 image_sub_.getNumPublishers() > 0 && depth_sub_.getNumPublishers() > 0 &&
                 patch_sub_.getNumPublishers() > 0;
        },
        10.0));
    placeCamera(-3.0);

    rc::PatchSampling sampling;
    sampling.samples = kSamplesA;
    sphere_a_ = rc::sampleSphere(kCenterA, kRadiusA, sampling);
    sphere_a_.colors.assign(sphere_a_.size(), rc::Rgba{255, 0, 0, 255});
    sampling.samples = kSamplesB;
    sphere_b_ = rc::sampleSphere(kCenterB, kRadiusB, sampling);
    sphere_b_.colors.assign(sphere_b_.size(), rc::Rgba{0, 255, 0, 255});
  }

  /// The camera at (0, 0, z) looking along +z (optical frame = world orientation).
  void placeCamera(double z) {
    geometry_msgs::TransformStamped tf;
    tf.header.stamp = ros::Time::now();
    tf.header.frame_id = "world";
    tf.child_frame_id = "test_camera";
    tf.transform.translation.z = z;
    tf.transform.rotation.w = 1.0;
    tf_broadcaster_.sendTransform(tf);
    camera_ = rc::Camera::perspective(kWidth, kHeight, kFovDegrees * M_PI / 180.0);
    camera_.near_clip = 0.01;
    camera_.far_clip = 100.0;
    camera_.world_T_camera = Eigen::Translation3d(0, 0, z) * Eigen::Isometry3d::Identity();
  }

  bool waitFor(const std::function<bool()>& done, double seconds) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
    while (ros::ok() && ros::WallTime::now() < end) {
      ros::spinOnce();
      if (done()) return true;
      ros::WallDuration(0.01).sleep();
    }
    return done();
  }

  size_t frameCount() {
    std::lock_guard<std::mutex> lock(mutex_);
    return stats_.size();
  }

  /// Waits for the first frame after `after` frames whose stats satisfy `accept`, and its images.
  Frame waitForFrame(size_t after, const std::function<bool(const CsgRenderStats&)>& accept) {
    size_t index = std::numeric_limits<size_t>::max();
    const bool got = waitFor(
        [&] {
          std::lock_guard<std::mutex> lock(mutex_);
          for (size_t i = after; i < stats_.size() && index == std::numeric_limits<size_t>::max(); ++i)
            if (accept(stats_[i])) index = i;
          return index != std::numeric_limits<size_t>::max() && images_.size() > index &&
                 depths_.size() > index && patches_.size() > index;
        },
        15.0);
    Frame frame;
    if (!got) {
      ADD_FAILURE() << "no matching frame (node dead or input not accepted?)";
      return frame;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    frame.stats = stats_[index];
    frame.image = images_[index];
    frame.depth = depths_[index];
    frame.patch = patches_[index];
    return frame;
  }

  ros::Time publish(ros::Publisher& pub, const rc::SurfelCloud& cloud,
                    rc::PointCloud2Layout layout = rc::PointCloud2Layout::kPointSurfel,
                    const std::string& frame = "world") {
    rc::SurfelCloud c = cloud;
    c.frame_id = frame;
    ros::Time stamp = ros::Time::now();
    if (stamp <= last_stamp_) stamp = last_stamp_ + ros::Duration(0, 1000);
    last_stamp_ = stamp;
    c.stamp_ns = stamp.toNSec();
    pub.publish(rc::PointCloud2Converter::toMessage(c, layout));
    return stamp;
  }

  relaxed_connectivity::SetCsgTree setTree(const std::string& expression) {
    relaxed_connectivity::SetCsgTree srv;
    srv.request.expression = expression;
    EXPECT_TRUE(set_tree_.call(srv));
    return srv;
  }

  rc::AnalyticImages reference(const std::string& expression) const {
    rc::AnalyticCsgCaster caster(
        {rc::AnalyticSolid::sphere(kCenterA, kRadiusA), rc::AnalyticSolid::sphere(kCenterB, kRadiusB)},
        rc::CsgTree::parse(expression));
    return rc::castImage(caster, camera_);
  }

  /// Compares a frame with the analytic reference away from its silhouettes and creases: pixels whose
  /// (2 * band + 1)^2 neighbourhood in the reference is all background or all surface without depth jumps
  /// > 5 cm must agree in coverage, and covered ones in depth within 1 cm. Returns the interior pixel count.
  size_t expectMatchesInterior(const Frame& f, const rc::AnalyticImages& ref, int band,
                               double min_agreement) {
    size_t interior_surface = 0, interior_background = 0, coverage_errors = 0, depth_agree = 0;
    double max_error = 0;
    for (int v = band; v < int(kHeight) - band; ++v)
      for (int u = band; u < int(kWidth) - band; ++u) {
        const float r = ref.depth[v * kWidth + u];
        bool uniform = true;
        for (int dv = -band; dv <= band && uniform; ++dv)
          for (int du = -band; du <= band && uniform; ++du) {
            const float q = ref.depth[(v + dv) * kWidth + (u + du)];
            uniform = std::isfinite(q) == std::isfinite(r) && (!std::isfinite(r) || std::abs(q - r) < 0.05);
          }
        if (!uniform) continue;
        const float d = depthAt(*f.depth, uint32_t(u), uint32_t(v));
        if (!std::isfinite(r)) {
          ++interior_background;
          coverage_errors += std::isfinite(d);
          continue;
        }
        ++interior_surface;
        if (!std::isfinite(d)) {
          ++coverage_errors;
          continue;
        }
        max_error = std::max(max_error, double(std::abs(d - r)));
        depth_agree += std::abs(d - r) < 0.01;
      }
    const double agreement = double(depth_agree) / std::max<size_t>(1, interior_surface);
    std::printf(
        "[ csg ] \"%s\": %zu interior surface + %zu background pixels, %zu coverage errors, "
        "depth within 1 cm %.4f (max error %.4f m)\n",
        f.stats.csg.c_str(), interior_surface, interior_background, coverage_errors, agreement, max_error);
    EXPECT_EQ(coverage_errors, 0u) << f.stats.csg;
    EXPECT_GT(agreement, min_agreement) << f.stats.csg;
    return interior_surface;
  }

  static size_t differingPixels(const sensor_msgs::Image& a, const sensor_msgs::Image& b) {
    size_t n = 0;
    for (size_t i = 0; i + 3 <= a.data.size(); i += 3) n += std::memcmp(&a.data[i], &b.data[i], 3) != 0;
    return n;
  }

  std::mutex mutex_;
  std::vector<ImageConstPtr> images_, depths_, patches_;
  sensor_msgs::CameraInfoConstPtr info_;
  std::vector<CsgRenderStats> stats_;
  ros::Subscriber image_sub_, depth_sub_, patch_sub_, info_sub_, stats_sub_;
  ros::Publisher pub_a_, pub_b_, pub_surfels_;
  ros::ServiceClient set_tree_;
  tf2_ros::StaticTransformBroadcaster tf_broadcaster_;
  rc::Camera camera_;
  rc::SurfelCloud sphere_a_, sphere_b_;
  ros::Time last_stamp_;
};

TEST_F(CsgRendererNode, RendersTreesRejectsBadInputAndIdles) {
  const uint32_t cu = kWidth / 2, cv = kHeight / 2;  // pixel next to the optical axis

  // 1. Tree "0" (the initial parameter): only patch 0 is seen, at the analytic depth.
  publish(pub_a_, sphere_a_);
  const ros::Time stamp_b = publish(pub_b_, sphere_b_);
  Frame f0 = waitForFrame(0, [&](const CsgRenderStats& s) { return s.header.stamp == stamp_b; });
  ASSERT_TRUE(f0.image && f0.depth && f0.patch);
  EXPECT_EQ(f0.stats.csg, "0");
  EXPECT_EQ(f0.stats.patches, 1u);
  EXPECT_EQ(f0.stats.surfels, kSamplesA);
  EXPECT_EQ(f0.image->header.frame_id, "test_camera");
  EXPECT_EQ(f0.image->header.stamp, stamp_b) << "stamp = latest input stamp";
  EXPECT_EQ(f0.image->encoding, sensor_msgs::image_encodings::RGB8);
  EXPECT_EQ(f0.depth->encoding, sensor_msgs::image_encodings::TYPE_32FC1);
  EXPECT_EQ(f0.patch->encoding, sensor_msgs::image_encodings::TYPE_32SC1);
  for (const ImageConstPtr& im : {f0.image, f0.depth, f0.patch}) {
    EXPECT_EQ(im->width, kWidth);
    EXPECT_EQ(im->height, kHeight);
    EXPECT_EQ(im->data.size(), size_t(im->step) * kHeight);
  }
  EXPECT_TRUE(std::isnan(depthAt(*f0.depth, 0, 0))) << "background depth must be NaN";
  EXPECT_EQ(patchAt(*f0.patch, 0, 0), -1);
  size_t patch1_pixels = 0;
  for (uint32_t v = 0; v < kHeight; ++v)
    for (uint32_t u = 0; u < kWidth; ++u) patch1_pixels += patchAt(*f0.patch, u, v) == 1;
  EXPECT_EQ(patch1_pixels, 0u) << "patch 1 is not in the tree \"0\"";
  const rc::AnalyticImages ref0 = reference("0");
  EXPECT_NEAR(depthAt(*f0.depth, cu, cv), ref0.depth[cv * kWidth + cu], 0.01);
  EXPECT_GT(expectMatchesInterior(f0, ref0, 2, 0.99), 4000u);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ASSERT_TRUE(info_);
    EXPECT_EQ(info_->header.frame_id, "test_camera");
    EXPECT_NEAR(info_->K[0], camera_.fx, 1e-9);
    EXPECT_NEAR(info_->K[2], camera_.cx, 1e-9);
  }

  // 2. "0 - 1": patch 1 carves a cavity; the centre pixel sees its far wall at the analytic depth.
  size_t before = frameCount();
  relaxed_connectivity::SetCsgTree srv = setTree("0 - 1");
  EXPECT_TRUE(srv.response.success) << srv.response.message;
  Frame f1 = waitForFrame(before, [](const CsgRenderStats& s) { return s.csg == "0 - 1"; });
  ASSERT_TRUE(f1.image && f1.depth && f1.patch);
  EXPECT_EQ(f1.stats.patches, 2u);
  EXPECT_EQ(f1.stats.surfels, kSamplesA + kSamplesB);
  EXPECT_GT(f1.stats.clipped_fragments, 0u);
  EXPECT_GT(differingPixels(*f0.image, *f1.image), 500u);
  const rc::AnalyticImages ref1 = reference("0 - 1");
  const double carved = ref1.depth[cv * kWidth + cu];
  EXPECT_NEAR(carved, 3.0 - 0.4, 1e-3);  // the far side of sphere 1 (z = -0.4) seen from z = -3
  EXPECT_NEAR(depthAt(*f1.depth, cu, cv), carved, 0.01);
  EXPECT_EQ(patchAt(*f1.patch, cu, cv), 1);
  EXPECT_GT(expectMatchesInterior(f1, ref1, 2, 0.99), 2500u);

  // 3. A bad expression is rejected with the parser's message; the old tree keeps rendering.
  before = frameCount();
  srv = setTree("0 - (1");
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("column"), std::string::npos) << srv.response.message;
  const ros::Time stamp3 = publish(pub_b_, sphere_b_);
  Frame f3 = waitForFrame(before, [&](const CsgRenderStats& s) { return s.header.stamp == stamp3; });
  EXPECT_EQ(f3.stats.csg, "0 - 1");
  EXPECT_EQ(f3.stats.rejected_inputs, 1u);
  EXPECT_NE(f3.stats.last_error.find("0 - (1"), std::string::npos) << f3.stats.last_error;
  if (f3.depth) {
    EXPECT_NEAR(depthAt(*f3.depth, cu, cv), carved, 0.01);
  }

  // 4. Bad clouds: no normals (patch topic), no patch_id (surfels topic), a NaN position, an unknown frame.
  //    Each is rejected with its reason; the last good clouds stay.
  rc::SurfelCloud no_normals;  // sent in the compact layout, which has no normal fields at all
  no_normals.positions = sphere_a_.positions;
  no_normals.radii = sphere_a_.radii;
  rc::SurfelCloud no_patch_id = sphere_a_;
  rc::SurfelCloud with_nan = sphere_a_;
  with_nan.positions[17].x() = std::numeric_limits<double>::quiet_NaN();
  struct BadCase {
    ros::Publisher* pub;
    const rc::SurfelCloud* cloud;
    rc::PointCloud2Layout layout;
    const char* reason;
    std::string frame = "world";
  };
  // An unknown frame: the cloud waits in the tf message filter (tf_queue_size 1, the .test) until the next
  // such cloud pushes it out.
  const BadCase bad_cases[] = {
      {&pub_a_, &no_normals, rc::PointCloud2Layout::kCompact, "no normals"},
      {&pub_surfels_, &no_patch_id, rc::PointCloud2Layout::kPointSurfel, "no patch_id"},
      {&pub_a_, &with_nan, rc::PointCloud2Layout::kPointSurfel, "non-finite positions"},
      {&pub_a_, &sphere_a_, rc::PointCloud2Layout::kPointSurfel, "no transform from 'no_such_frame'",
       "no_such_frame"}};
  uint32_t rejected = 1;
  for (const BadCase& bad : bad_cases) {
    before = frameCount();
    publish(*bad.pub, *bad.cloud, bad.layout, bad.frame);
    if (bad.frame != "world") publish(*bad.pub, *bad.cloud, bad.layout, bad.frame);
    ros::WallDuration(0.2).sleep();
    const ros::Time trigger = publish(pub_b_, sphere_b_);  // a good cloud: a new frame with the kept state
    Frame f = waitForFrame(before, [&](const CsgRenderStats& s) { return s.header.stamp == trigger; });
    ++rejected;
    EXPECT_EQ(f.stats.rejected_inputs, rejected) << bad.reason;
    EXPECT_NE(f.stats.last_error.find(bad.reason), std::string::npos) << f.stats.last_error;
    EXPECT_EQ(f.stats.surfels, kSamplesA + kSamplesB) << "the last good patch 0 must stay";
    if (f.depth) {
      EXPECT_NEAR(depthAt(*f.depth, cu, cv), carved, 0.01);
    }
  }

  // /diagnostics counts the rejections per input: three on patch_a, one on surfels.
  {
    ros::NodeHandle nh;
    std::map<std::string, std::string> rejected;  // status name -> its "rejected" value
    ros::Subscriber diagnostics = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 20, [&](const diagnostic_msgs::DiagnosticArrayConstPtr& m) {
          for (const auto& status : m->status)
            for (const auto& kv : status.values)
              if (kv.key == "rejected") rejected[status.name] = kv.value;
        });
    EXPECT_TRUE(waitFor(
        [&] {
          return rejected["csg_renderer: input patch_a"] == "3" &&
                 rejected["csg_renderer: input surfels"] == "1";
        },
        5.0))
        << rejected["csg_renderer: input patch_a"] << " / " << rejected["csg_renderer: input surfels"];
  }

  // 5. Nothing changes: no frame over a quiet second.
  ros::WallDuration(0.3).sleep();
  waitFor([] { return false; }, 0.2);
  before = frameCount();
  waitFor([] { return false; }, 1.0);
  EXPECT_EQ(frameCount(), before) << "re-rendered although nothing changed";

  // 6. The camera moves: exactly one new frame, at the new analytic depth, then quiet again.
  placeCamera(-3.5);
  Frame f6 = waitForFrame(before, [](const CsgRenderStats&) { return true; });
  if (f6.depth) {
    EXPECT_NEAR(depthAt(*f6.depth, cu, cv), carved + 0.5, 0.01);
  }
  waitFor([] { return false; }, 1.0);
  EXPECT_EQ(frameCount(), before + 1);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    EXPECT_EQ(images_.size(), stats_.size());
  }

  // 7. dynamic_reconfigure (Splat.cfg): new splat settings re-render once with nothing else changed, and the
  //    answer carries them; back-face culling with the difference "0 - 1" is refused and answered as off.
  ros::NodeHandle nh;
  ros::ServiceClient reconfigure =
      nh.serviceClient<dynamic_reconfigure::Reconfigure>("csg_renderer/set_parameters");
  ASSERT_TRUE(reconfigure.waitForExistence(ros::Duration(10)));
  dynamic_reconfigure::Reconfigure wider = rc::reconfigureRequest({{"lowpass_variance", 1.0}});
  before = frameCount();
  ASSERT_TRUE(reconfigure.call(wider));
  EXPECT_EQ(rc::doubleOf(wider.response.config, "lowpass_variance"), 1.0);
  waitForFrame(before, [](const CsgRenderStats&) { return true; });
  waitFor([] { return false; }, 0.5);
  EXPECT_EQ(frameCount(), before + 1) << "one frame for the new settings";
  dynamic_reconfigure::Reconfigure culling = rc::reconfigureRequest({}, {}, {{"backface_culling", true}});
  ASSERT_TRUE(reconfigure.call(culling));
  EXPECT_EQ(rc::boolOf(culling.response.config, "backface_culling"), 0)
      << "culling with a difference accepted";
}

}  // namespace

// With back-face culling on, a tree with a difference or complement is refused with the reason and the node
// keeps its tree; intersections and unions are accepted.
TEST(CsgRendererCulling, DifferencesAreRefusedIntersectionsAccepted) {
  ros::NodeHandle nh;
  ros::ServiceClient set_tree =
      nh.serviceClient<relaxed_connectivity::SetCsgTree>("culling_renderer/set_csg_tree");
  ASSERT_TRUE(set_tree.waitForExistence(ros::Duration(30.0)));
  relaxed_connectivity::SetCsgTree difference;
  difference.request.expression = "0 - 1";
  ASSERT_TRUE(set_tree.call(difference));
  EXPECT_FALSE(difference.response.success);
  EXPECT_NE(difference.response.message.find("backface_culling"), std::string::npos)
      << difference.response.message;
  relaxed_connectivity::SetCsgTree complement;
  complement.request.expression = "!0";
  ASSERT_TRUE(set_tree.call(complement));
  EXPECT_FALSE(complement.response.success);
  relaxed_connectivity::SetCsgTree union_tree;
  union_tree.request.expression = "0 | 1";
  ASSERT_TRUE(set_tree.call(union_tree));
  EXPECT_TRUE(union_tree.response.success) << union_tree.response.message;
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "csg_renderer_node_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
