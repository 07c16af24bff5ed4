#!/usr/bin/env bash
# The core modules must not include ROS or PCL headers (they build on machines without either).
cd "$(dirname "$0")/.."
hits=$(grep -rnE '#include *[<"](ros/|pcl/|pcl_conversions|sensor_msgs/|tf2|nodelet/)' src/core src/io src/surface src/scan src/render src/sph src/fem)
if [ -n "$hits" ]; then
  echo "ROS/PCL includes in the core:"; echo "$hits"; exit 1
fi
echo "core is ROS-free: $(find src/core src/io src/surface src/scan src/render src/sph src/fem -name '*.cpp' | wc -l) sources checked"
