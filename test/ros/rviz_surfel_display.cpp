// The SurfelCloud rviz display (src/ros/rviz) inside rviz's own VisualizationManager and RenderPanel, under
// Xvfb: it loads through the plugin factory (rviz_plugins.xml, package.xml export), draws three discs of a
// PointCloud2 placed by tf where a top-down orthographic view puts them, round and in their colours, and
// keeps the last good cloud when a bad one comes.
#include <OGRE/OgreImage.h>
#include <OGRE/OgreRenderWindow.h>
#include <OGRE/OgreRoot.h>
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rviz/display.h>
#include <rviz/display_group.h>
#include <rviz/failed_display.h>
#include <rviz/render_panel.h>
#include <rviz/view_controller.h>
#include <rviz/view_manager.h>
#include <rviz/visualization_manager.h>
#include <rviz/yaml_config_reader.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <QApplication>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>

#include "relaxed_connectivity/ros/point_cloud2_converter.h"
#include "relaxed_connectivity/ros/rviz/surfel_cloud_display.h"

namespace rc {
namespace {

constexpr int kWidth = 400, kHeight = 300;
constexpr double kScale = 100;  // pixels per metre of the top-down view

QApplication* application = nullptr;

struct Viewer {
  Viewer() {
    panel = std::make_unique<rviz::RenderPanel>();
    panel->resize(kWidth, kHeight);
    panel->show();
    manager = std::make_unique<rviz::VisualizationManager>(panel.get());
    panel->initialize(manager->getSceneManager(), manager.get());
    manager->initialize();
    manager->startUpdate();
    manager->setFixedFrame("world");
    manager->getViewManager()->setCurrentViewControllerType("rviz/TopDownOrtho");
    rviz::ViewController* view = manager->getViewManager()->getCurrent();
    view->subProp("Scale")->setValue(kScale);
    view->subProp("X")->setValue(0.0);
    view->subProp("Y")->setValue(0.0);
    view->subProp("Angle")->setValue(0.0);
  }
  /// Spins ROS and Qt for `seconds` or until done().
  template <class Done>
  bool run(double seconds, Done&& done) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
      ros::spinOnce();
      application->processEvents();
      if (done()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return false;
  }
  /// The rendered image, RGB rows.
  std::vector<std::array<uint8_t, 3>> grab() {
    manager->queueRender();
    run(0.5, [] { return false; });
    Ogre::RenderWindow* window = panel->getRenderWindow();
    const uint32_t w = window->getWidth(), h = window->getHeight();
    std::vector<uint8_t> bytes(size_t(w) * h * 3);
    Ogre::PixelBox box(w, h, 1, Ogre::PF_BYTE_RGB, bytes.data());
    window->copyContentsToMemory(Ogre::Box(0, 0, w, h), box);
    width = w;
    height = h;
    std::vector<std::array<uint8_t, 3>> pixels(size_t(w) * h);
    for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = {bytes[3 * i], bytes[3 * i + 1], bytes[3 * i + 2]};
    const char* home = std::getenv("ROS_HOME");
    const std::string path = std::string(home ? home : "/tmp") + "/rviz_surfel_display.png";
    window->writeContentsToFile(path);
    std::printf("screenshot %ux%u: %s\n", w, h, path.c_str());
    return pixels;
  }
  std::unique_ptr<rviz::RenderPanel> panel;
  std::unique_ptr<rviz::VisualizationManager> manager;
  uint32_t width = 0, height = 0;
};

/// One viewer for the process (rviz's materials are global: a second manager would create them twice).
Viewer& sharedViewer() {
  static Viewer viewer;
  viewer.manager->removeAllDisplays();
  return viewer;
}

SurfelCloud threeDiscs() {
  SurfelCloud c;  // in frame "discs", 0.5 m above world: x 1 -> world x, y -> world y
  c.positions = {Vec3(-0.6, 0, 0), Vec3(0.6, 0, 0), Vec3(0, 0.6, 0)};
  c.normals = {Vec3::UnitZ(), Vec3::UnitZ(), Vec3::UnitZ()};
  c.radii = {0.25, 0.25, 0.25};
  c.colors = {{230, 20, 20, 255}, {20, 230, 20, 255}, {20, 20, 230, 255}};
  return c;
}

TEST(RvizSurfelDisplay, LoadsAndDrawsRoundDiscsInTheirColours) {
  ros::NodeHandle nh;
  tf2_ros::StaticTransformBroadcaster tf;
  geometry_msgs::TransformStamped t;
  t.header.frame_id = "world";
  t.child_frame_id = "discs";
  t.transform.translation.x = 0.5;  // the cloud's frame is shifted by +0.5 m in x
  t.transform.rotation.w = 1;
  tf.sendTransform(t);
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("/test_surfels", 1, true);

  Viewer& viewer = sharedViewer();
  rviz::Display* display = viewer.manager->createDisplay("relaxed_connectivity/SurfelCloud", "Surfels", true);
  ASSERT_NE(display, nullptr);
  auto* surfels = dynamic_cast<SurfelCloudDisplay*>(display);
  ASSERT_NE(surfels, nullptr) << "not the plugin's class (a failed display?): "
                              << display->getClassId().toStdString();
  display->subProp("Topic")->setValue("/test_surfels");
  display->subProp("Lighting")->setValue(false);  // flat colours to compare

  sensor_msgs::PointCloud2 msg;
  PointCloud2Converter::toMessage(threeDiscs(), msg);
  msg.header.frame_id = "discs";
  msg.header.stamp = ros::Time(0);
  pub.publish(msg);
  ASSERT_TRUE(viewer.run(20, [&] { return surfels->discs() == 3; })) << surfels->discs() << " discs";
  const auto image = viewer.grab();
  ASSERT_EQ(viewer.width, uint32_t(kWidth));
  // World (x, y) -> pixel: the view centre at the image centre, x to the right, y up.
  auto at = [&](double x, double y) {
    const int u = int(std::lround(kWidth / 2.0 + kScale * x)),
              v = int(std::lround(kHeight / 2.0 - kScale * y));
    return image[size_t(v) * kWidth + u];
  };
  auto near = [](const std::array<uint8_t, 3>& p, std::array<int, 3> rgb) {
    for (int c = 0; c < 3; ++c)
      if (std::abs(int(p[c]) - rgb[c]) > 12) return false;
    return true;
  };
  const std::array<uint8_t, 3> background = at(-1.8, -1.3);
  std::printf("background %d %d %d, red centre %d %d %d\n", background[0], background[1], background[2],
              at(-0.1, 0)[0], at(-0.1, 0)[1], at(-0.1, 0)[2]);
  // Disc centres (world x = cloud x + 0.5): red at -0.1, green at 1.1, blue at (0.5, 0.6).
  EXPECT_TRUE(near(at(-0.1, 0), {230, 20, 20}));
  EXPECT_TRUE(near(at(1.1, 0), {20, 230, 20}));
  EXPECT_TRUE(near(at(0.5, 0.6), {20, 20, 230}));
  // Inside the discs near their rims, and the quads' corners (outside the discs) empty.
  EXPECT_TRUE(near(at(-0.1 + 0.2, 0), {230, 20, 20}));
  EXPECT_TRUE(near(at(-0.1, -0.2), {230, 20, 20}));
  for (const auto& [x, y] : std::vector<std::pair<double, double>>{
           {-0.1 + 0.22, 0.22}, {-0.1 - 0.22, -0.22}, {1.1 + 0.22, -0.22}, {0.5 - 0.22, 0.6 + 0.22}}) {
    const auto p = at(x, y);
    EXPECT_TRUE(near(p, {background[0], background[1], background[2]}))
        << "corner (" << x << ", " << y << "): " << int(p[0]) << " " << int(p[1]) << " " << int(p[2]);
  }
  // Counted: red pixels cover the disc's area pi r^2 (within the edge pixels).
  size_t red = 0;
  for (const auto& p : image) red += near(p, {230, 20, 20});
  const double area = M_PI * 25.0 * 25.0;  // r = 0.25 m = 25 px
  EXPECT_NEAR(double(red), area, 0.1 * area);

  // A scalar field through viridis: x from the red disc's (lowest) to the green one's (highest).
  display->subProp("Color Field")->setValue("x");
  viewer.run(1, [] { return false; });
  const auto field_image = viewer.grab();
  auto field_at = [&](double x, double y) {
    const int u = int(std::lround(kWidth / 2.0 + kScale * x)),
              v = int(std::lround(kHeight / 2.0 - kScale * y));
    return field_image[size_t(v) * kWidth + u];
  };
  EXPECT_TRUE(near(field_at(-0.1, 0), {68, 1, 84}));      // viridis(0)
  EXPECT_TRUE(near(field_at(1.1, 0), {253, 231, 37}));    // viridis(1)
  EXPECT_TRUE(near(field_at(0.5, 0.6), {33, 144, 141}));  // viridis(0.5)
  EXPECT_NEAR(display->subProp("Min Value")->getValue().toDouble(), -0.6, 1e-6);
  EXPECT_NEAR(display->subProp("Max Value")->getValue().toDouble(), 0.6, 1e-6);

  // A malformed cloud (half its data) is refused with the reason in the status; the last good one stays.
  sensor_msgs::PointCloud2 bad = msg;
  bad.data.resize(bad.data.size() / 2);
  pub.publish(bad);
  viewer.run(2, [] { return false; });
  EXPECT_EQ(surfels->discs(), 3u);
}

// Every shipped rviz config (config/rviz) loads in rviz with each of its displays created (none failed: a
// missing plugin would show as a FailedDisplay); the surfel topics use the SurfelCloud display.
TEST(RvizSurfelDisplay, EveryShippedConfigLoads) {
  Viewer& viewer = sharedViewer();
  int surfel_displays = 0, configs = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(RC_SOURCE_DIR) + "/config/rviz")) {
    if (entry.path().extension() != ".rviz") continue;
    SCOPED_TRACE(entry.path().filename().string());
    ++configs;
    rviz::YamlConfigReader reader;
    rviz::Config config;
    reader.readFile(config, QString::fromStdString(entry.path().string()));
    ASSERT_FALSE(reader.error()) << reader.errorMessage().toStdString();
    viewer.manager->removeAllDisplays();
    viewer.manager->load(config.mapGetChild("Visualization Manager"));
    rviz::DisplayGroup* root = viewer.manager->getRootDisplayGroup();
    ASSERT_GT(root->numDisplays(), 0);
    for (int i = 0; i < root->numDisplays(); ++i) {
      rviz::Display* d = root->getDisplayAt(i);
      EXPECT_EQ(dynamic_cast<rviz::FailedDisplay*>(d), nullptr)
          << d->getName().toStdString() << " (" << d->getClassId().toStdString() << ") failed to load";
      surfel_displays += dynamic_cast<SurfelCloudDisplay*>(d) != nullptr;
    }
  }
  EXPECT_EQ(configs, 8);
  EXPECT_EQ(surfel_displays, 10);  // scan 2, paint_session 3, paint_brush 3, csg_demo 1, shell_demo 1
  viewer.manager->removeAllDisplays();
}

/// Median of the time Ogre takes for a frame of the viewer's scene [ms] (llvmpipe here: OpenGL in software).
double medianFrameMs(Viewer& viewer, int frames) {
  std::vector<double> ms;
  for (int f = 0; f < frames; ++f) {
    const auto start = std::chrono::steady_clock::now();
    Ogre::Root::getSingleton().renderOneFrame();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    application->processEvents();
  }
  std::sort(ms.begin(), ms.end());
  return ms[ms.size() / 2];
}

// Measured, not asserted (no timing thresholds in tests): a 750k-surfel sphere as discs, against rviz's own
// PointCloud2 display (flat squares, no orientation) on the same message, the displays shown one at a time.
TEST(RvizSurfelDisplay, SevenHundredFiftyThousandSurfelsMeasured) {
  constexpr int kSurfels = 750000;
  SurfelCloud sphere;
  const double golden = M_PI * (3.0 - std::sqrt(5.0)), radius = 1.5 * std::sqrt(4.0 / kSurfels);
  for (int i = 0; i < kSurfels; ++i) {
    const double z = 1 - 2 * (i + 0.5) / kSurfels, r = std::sqrt(1 - z * z), phi = golden * i;
    const Vec3 n(r * std::cos(phi), r * std::sin(phi), z);
    sphere.positions.push_back(n);
    sphere.normals.push_back(n);
    sphere.radii.push_back(radius);
    sphere.colors.push_back({uint8_t(128 + 127 * n.x()), uint8_t(128 + 127 * n.y()), 200, 255});
  }
  sensor_msgs::PointCloud2 msg;
  PointCloud2Converter::toMessage(sphere, msg);
  msg.header.frame_id = "world";
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("/big_surfels", 1, true);
  pub.publish(msg);
  Viewer& viewer = sharedViewer();
  rviz::Display* discs = viewer.manager->createDisplay("relaxed_connectivity/SurfelCloud", "Discs", true);
  discs->subProp("Topic")->setValue("/big_surfels");
  auto* surfels = dynamic_cast<SurfelCloudDisplay*>(discs);
  ASSERT_NE(surfels, nullptr);
  ASSERT_TRUE(viewer.run(60, [&] { return surfels->discs() == size_t(kSurfels); })) << surfels->discs();
  const double disc_build = surfels->lastBuildMilliseconds(), disc_frame = medianFrameMs(viewer, 5);
  discs->setEnabled(false);
  rviz::Display* points = viewer.manager->createDisplay("rviz/PointCloud2", "Points", true);
  points->subProp("Topic")->setValue("/big_surfels");
  viewer.run(10, [] { return false; });  // (no hook tells when it has built its cloud: ten seconds)
  const double point_frame = medianFrameMs(viewer, 5);
  std::printf(
      "| surfels | display | build ms (convert, geometry, upload) | frame ms (median of 5, %s) |\n"
      "|---|---|---|---|\n| %d | relaxed_connectivity/SurfelCloud (discs) | %.0f | %.0f |\n"
      "| %d | rviz/PointCloud2 (flat squares) | - | %.0f |\n",
      "OpenGL of this machine", kSurfels, disc_build, disc_frame, kSurfels, point_frame);
  EXPECT_GT(disc_frame, 0);
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "rviz_surfel_display_test");
  QApplication app(argc, argv);
  rc::application = &app;
  return RUN_ALL_TESTS();
}
