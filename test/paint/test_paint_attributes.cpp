// Paint attributes on a SurfelCloud: written, read back, and bit-exact through a PLY file.
#include "relaxed_connectivity/paint/paint_attributes.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>

#include "paint_test_surfaces.h"
#include "relaxed_connectivity/io/ply_io.h"

namespace rc {
namespace {

TEST(PaintAttributes, SurviveAPlyRoundTripBitwise) {
  SurfelCloud cloud = paint_test::planeCloud(0.004, 0.001);
  cloud.colors.assign(cloud.size(), Rgba{255, 128, 0, 255});
  PaintState initial;
  initial.dry_volume = 0.5;
  addPaintAttributes(cloud, initial);
  ASSERT_TRUE(hasPaintAttributes(cloud));
  EXPECT_EQ(readPaint(cloud, 3).dry.rgb, Vec3(1.0, 128 / 255.0, 0.0));  // the surfel's own colour is C_d
  for (size_t i = 0; i < cloud.size(); ++i) {
    PaintState p = readPaint(cloud, i);
    p.wet.rgb = Vec3(0.1 + 1e-17 * double(i), 1.0 / 3.0, std::sqrt(2.0) / 2);  // values no float keeps
    p.wet_volume = std::exp(-double(i) / 7);
    p.optical_density = 1.0 / (i + 3.0);
    p.wet.shininess = 40.0 / 3.0;
    p.dry.reflectivity = 0.1 * std::sqrt(double(i));
    p.transfer_rate = i % 3 == 0 ? -1.0 : 4.0 / 3.0;  // set on some surfels (tau), not on others
    writePaint(cloud, i, p);
  }
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("rc_paint_attributes_" + std::to_string(::getpid()) + ".ply"))
                               .string();
  writePlyCloud(path, cloud);
  const SurfelCloud back = readPlyCloud(path);
  std::filesystem::remove(path);
  ASSERT_TRUE(hasPaintAttributes(back));
  for (size_t i = 0; i < cloud.size(); ++i)
    EXPECT_EQ(readPaint(back, i), readPaint(cloud, i)) << "surfel " << i;
  EXPECT_EQ(readPaint(back, 1).transfer_rate, 4.0 / 3.0);
  // The transfer rate column is optional: without it every surfel reads "not set".
  SurfelCloud without = back;
  without.attributes.remove(kPaintTransferRate);
  ASSERT_TRUE(hasPaintAttributes(without));
  EXPECT_EQ(readPaint(without, 1).transfer_rate, -1.0);
}

TEST(PaintAttributes, MissingColumnsAndBadIndicesAreNamed) {
  SurfelCloud cloud = paint_test::planeCloud(0.002, 0.001);
  EXPECT_FALSE(hasPaintAttributes(cloud));
  try {
    readPaint(cloud, 0);
    FAIL() << "read paint from a cloud without paint columns";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("paint_wet_rgb"), std::string::npos) << e.what();
  }
  addPaintAttributes(cloud, PaintState());
  EXPECT_THROW(readPaint(cloud, cloud.size()), std::invalid_argument);
  // Adding again replaces the columns (no duplicate names).
  addPaintAttributes(cloud, PaintState());
  EXPECT_TRUE(hasPaintAttributes(cloud));
}

}  // namespace
}  // namespace rc
