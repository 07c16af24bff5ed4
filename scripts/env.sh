# Sourced by the scripts: system tools first (a pyenv python3 on PATH breaks catkin and rostest).
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
export PYTHON_EXECUTABLE=/usr/bin/python3
RC_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
RC_JOBS=${RC_JOBS:-$(nproc)}
# The install space of the catkin package (scripts/check_install): outside the checkout, since roslaunch and
# rostest look for launch files anywhere below the package's folder (a copy there would be a second one).
RC_INSTALL_PREFIX=${RC_INSTALL_PREFIX:-/tmp/relaxed_connectivity_install_$(echo "$RC_ROOT" | md5sum | cut -c1-8)}
export RC_ROOT RC_JOBS RC_INSTALL_PREFIX
# ccache (installed by scripts/setup) keeps objects across branch switches and reconfigurations; the sloppiness
# lets it cache sources compiled with the precompiled headers.
rc_launcher=()
if command -v ccache >/dev/null; then
  rc_launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  export CCACHE_SLOPPINESS=pch_defines,time_macros,include_file_mtime,include_file_ctime
fi

# Configures and builds the core alone with plain CMake (no ROS): build/core (RC_TARGETS: only these targets).
rc_build_core() {
  cmake -S "$RC_ROOT" -B "$RC_ROOT/build/core" -DRC_WITH_ROS=OFF -DCMAKE_BUILD_TYPE=Release "${rc_launcher[@]}" \
    "$@" >/dev/null
  cmake --build "$RC_ROOT/build/core" -j "$RC_JOBS" ${RC_TARGETS:+--target $RC_TARGETS}
}

# Configures and builds the catkin package (the ROS layer, linked to the core libraries of build/core, which
# rc_build_core must have built first): build/ros, devel space in build/ros/devel (RC_TARGETS: only these targets).
rc_build_ros() {
  cmake -S "$RC_ROOT" -B "$RC_ROOT/build/ros" -DRC_WITH_ROS=ON -DCMAKE_BUILD_TYPE=Release \
    -DPYTHON_EXECUTABLE=/usr/bin/python3 -DRC_CORE_BUILD_DIR="$RC_ROOT/build/core" \
    -DCMAKE_INSTALL_PREFIX="$RC_INSTALL_PREFIX" "${rc_launcher[@]}" "$@" >/dev/null
  cmake --build "$RC_ROOT/build/ros" -j "$RC_JOBS" ${RC_TARGETS:+--target $RC_TARGETS}
}

# Makes the package's nodes, messages and launch files visible to rosrun/roslaunch/rostest.
rc_source_ros() {
  set +u
  # shellcheck disable=SC1091
  source "$RC_ROOT/build/ros/devel/setup.bash"
  set -u
  export ROS_PACKAGE_PATH="$RC_ROOT:${ROS_PACKAGE_PATH:-}"
  export ROS_HOME="$RC_ROOT/build/ros_home"
  export ROS_LOG_DIR="$RC_ROOT/build/ros_home/log"
}
