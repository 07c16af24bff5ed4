// libFuzzer target for the PointCloud2 converter (ros/point_cloud2_converter.h): any message a sender can
// build (arbitrary fields, names, offsets, datatypes and counts, point_step, row_step, width, height,
// is_bigendian, data of any length) is either read into a surfel cloud or refused with PointCloud2Error;
// nothing else (no crash, no read outside the data, no allocation beyond what the data holds). A cloud that
// was read is written back and read again with the same point count.
//
// Input layout: width, height, point_step, row_step (uint32 each, taken modulo a few sizes now and then so
// that consistent messages are common), is_bigendian, a field count, per field a name (from a dictionary of
// the names the converter knows, or raw bytes), offset, datatype and count; the rest is the data.
#include <fuzzer/FuzzedDataProvider.h>

#include <cstdint>
#include <string>
#include <vector>

#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace {

const std::vector<std::string>& knownNames() {
  static const std::vector<std::string> names = {
      "x",   "y",   "z",     "normal_x", "normal_y", "normal_z", "nx",         "ny",        "nz",   "rgba",
      "rgb", "red", "green", "blue",     "alpha",    "radius",   "confidence", "curvature", "t1x",  "t1y",
      "t1z", "t2x", "t2y",   "t2z",      "axis1_x",  "axis2_z",  "_",          "intensity", "label"};
  return names;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider in(data, size);
  sensor_msgs::PointCloud2 msg;
  const bool consistent = in.ConsumeBool();
  msg.width = in.ConsumeIntegral<uint32_t>();
  msg.height = in.ConsumeIntegral<uint32_t>();
  msg.point_step = in.ConsumeIntegral<uint32_t>();
  msg.row_step = in.ConsumeIntegral<uint32_t>();
  if (consistent) {  // small sizes that agree with each other, so the fuzzer reaches the per-point code
    msg.width %= 64;
    msg.height = msg.height % 4 + 1;
    msg.point_step %= 96;
    msg.row_step = msg.width * msg.point_step + msg.row_step % 8;
  }
  msg.is_bigendian = in.ConsumeBool();
  msg.is_dense = in.ConsumeBool();
  const size_t fields = in.ConsumeIntegralInRange<size_t>(0, 24);
  for (size_t f = 0; f < fields; ++f) {
    sensor_msgs::PointField field;
    const std::vector<std::string>& names = knownNames();
    field.name = in.ConsumeBool() ? names[in.ConsumeIntegralInRange<size_t>(0, names.size() - 1)]
                                  : in.ConsumeRandomLengthString(12);
    field.offset = consistent ? in.ConsumeIntegralInRange<uint32_t>(0, 100) : in.ConsumeIntegral<uint32_t>();
    field.datatype = in.ConsumeIntegralInRange<uint8_t>(0, 9);
    field.count = consistent ? in.ConsumeIntegralInRange<uint32_t>(0, 4) : in.ConsumeIntegral<uint32_t>();
    msg.fields.push_back(field);
  }
  const std::vector<uint8_t> bytes = in.ConsumeRemainingBytes<uint8_t>();
  if (consistent && msg.row_step > 0) {  // the size the layout asks for, from the bytes given (repeated)
    const size_t want = size_t(msg.row_step) * msg.height;
    msg.data.resize(want);
    for (size_t b = 0; b < want && !bytes.empty(); ++b) msg.data[b] = bytes[b % bytes.size()];
  } else {
    msg.data = bytes;
  }
  msg.header.frame_id = "fuzz";
  try {
    rc::SurfelCloud cloud;
    rc::PointCloud2Converter::fromMessage(msg, cloud);
    if (cloud.size() != size_t(msg.width) * msg.height) __builtin_trap();
    // What was read can be written and read back (attributes that do not fit a layout are refused).
    try {
      sensor_msgs::PointCloud2 back;
      rc::PointCloud2Converter::toMessage(cloud, back, rc::PointCloud2Layout::kCompact);
      if (rc::PointCloud2Converter::fromMessage(back).size() != cloud.size()) __builtin_trap();
    } catch (const rc::PointCloud2Error&) {
    }
  } catch (const rc::PointCloud2Error&) {
  }
  return 0;
}
