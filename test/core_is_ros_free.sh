#!/usr/bin/env bash
# The core modules (every folder of src/ but ros/) must not include ROS or PCL headers (they build on machines
# without either).
cd "$(dirname "$0")/.."
dirs=$(find src -mindepth 1 -maxdepth 1 -type d ! -name ros | sort)
# (relaxed_connectivity/ros/... is the ROS layer, relaxed_connectivity/<Upper>... a generated message header.)
hits=$(grep -rnE '#include *[<"](ros/|pcl/|pcl_conversions|sensor_msgs/|tf2|nodelet/|relaxed_connectivity/(ros/|[A-Z]))' $dirs)
if [ -n "$hits" ]; then
  echo "ROS/PCL includes in the core:"; echo "$hits"; exit 1
fi
echo "core is ROS-free: $(find $dirs -name '*.cpp' | wc -l) sources in $(echo $dirs | wc -w) folders checked"
