// Every node started with a bad parameter or file (issue 24): it exits with status 1 and a FATAL line that
// names the parameter, the file or the file:line:column, instead of running with a default or crashing.
// The test sets the private parameters on the master and starts each node's executable itself (the
// executables beside this test's), reading its output.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <sys/wait.h>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace {

struct Case {
  std::string node;                                                 // executable
  std::vector<std::pair<std::string, XmlRpc::XmlRpcValue>> params;  // private parameters
  std::string expected;                                             // in the FATAL line
};

XmlRpc::XmlRpcValue list(const std::vector<double>& values) {
  XmlRpc::XmlRpcValue v;
  v.setSize(int(values.size()));
  for (size_t i = 0; i < values.size(); ++i) v[int(i)] = values[i];
  return v;
}

std::string executableDir() {
  return std::filesystem::read_symlink("/proc/self/exe").parent_path().string();
}

/// Runs `node` as /bad_<node> (at most 20 s); returns its exit status (124: still running) and its output.
std::pair<int, std::string> run(const Case& c) {
  const std::string name = "bad_" + c.node;
  for (const auto& [key, value] : c.params) {
    XmlRpc::XmlRpcValue copy = value;
    ros::param::set("/" + name + "/" + key, copy);
  }
  const std::string command = "timeout 20 " + executableDir() + "/" + c.node + " __name:=" + name + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  std::string output;
  char buffer[4096];
  while (pipe && fgets(buffer, sizeof(buffer), pipe)) output += buffer;
  const int status = pipe ? pclose(pipe) : -1;
  for (const auto& [key, value] : c.params) ros::param::del("/" + name + "/" + key);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

TEST(NodesBadParameters, EveryNodeRefusesToStartAndSaysWhy) {
  const std::string bad_scene = "/tmp/rc_nodes_bad_parameters_shell.yaml";
  {
    std::ofstream out(bad_scene);
    out << "name: bad\nsource:\n  sheet: {size: [1, 1], spacing: 0.1}\nnodes: {spacing: 0.3}\n"
           "material: {stretch_stiffness: 1, bending_stiffness: 1, stiffnes: 3}\n";
  }
  const std::vector<Case> cases = {
      {"scanner", {{"model", "no_such_model"}}, "unknown model 'no_such_model'"},
      {"surfel_scene_publisher", {{"scene", "/nonexistent/scene.yaml"}}, "/nonexistent/scene.yaml"},
      {"surfel_estimator", {{"normal_k", 1}}, "normal_k must be >= 3"},
      {"csg_renderer", {{"max_rate", -1.0}}, "max_rate must be > 0"},
      {"paint_model",
       {{"brush", "/nonexistent/brush.yaml"}},
       "/nonexistent/brush.yaml: cannot open the file"},
      {"paint_model",
       {{"brush", std::string(RC_SOURCE_DIR) + "/config/paint/brushes/round.yaml"}, {"tf_wait", 0.0}},
       "tf_wait must be positive"},
      {"paint_renderer", {{"width", 0}}, "width and height must lie in"},
      {"haptic_driver", {{"device", "replay"}}, "~brush (a brush preset file"},
      {"haptic_driver",
       {{"brush", std::string(RC_SOURCE_DIR) + "/config/paint/brushes/round.yaml"}, {"device", "replay"}},
       "device replay needs ~stroke"},
      {"object_mover", {{"initial_pose", list({1, 2, 3, 4, 5})}}, "initial_pose must be"},
      {"mesh_converter", {{"simplify_error", -1.0}}, "simplify_error must be >= 0"},
      {"sph_sim", {{"scene", "/nonexistent/sph.yaml"}}, "/nonexistent/sph.yaml: cannot open the file"},
      {"fem_sim", {{"scene", "/nonexistent/fem.yaml"}}, "/nonexistent/fem.yaml: cannot open the file"},
      {"shell_sim", {{"scene", bad_scene}}, bad_scene + ":5:56: material: unknown key 'stiffnes'"},
  };
  for (const Case& c : cases) {
    const auto [status, output] = run(c);
    std::string fatal;
    for (size_t at = output.find("[FATAL]"); at != std::string::npos && fatal.empty();
         at = output.find("[FATAL]", at + 1))
      fatal = output.substr(at, output.find('\n', at) - at);
    std::printf("  %-24s exit %d: %s\n", c.node.c_str(), status, fatal.c_str());
    EXPECT_EQ(status, 1) << c.node << " (124: it kept running)\n" << output;
    EXPECT_NE(fatal.find(c.expected), std::string::npos) << c.node << ": '" << c.expected << "' not in\n"
                                                         << output;
  }
  std::filesystem::remove(bad_scene);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "nodes_bad_parameters");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
