#include "relaxed_connectivity/sph/sph_scene_reader_sections.h"

#include "relaxed_connectivity/io/cloud_io.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include <Eigen/Geometry>

#include "relaxed_connectivity/mesh/fast_winding_number.h"
#include "relaxed_connectivity/sph/sph_kernels.h"
#include "relaxed_connectivity/sph/sph_lattice.h"
#include "relaxed_connectivity/sph/sph_scene_builders.h"

namespace rc::sph_scene_reading {

void SceneReader::readOutput(const YAML::Node& node) {
  src_.allowKeys(node, {"particles", "surface"}, "output");
  if (const YAML::Node surface = node["surface"]) {
    if (!enabled("surface"))
      src_.fail(surface, "output.surface: needs 'surface' in the scene's 'enable' list");
    readSurface(surface);
  }
  const YAML::Node p = node["particles"];
  if (!p) return;
  src_.allowKeys(p, {"every", "formats"}, "output.particles");
  SphParticleOutput& out = scene_.output;
  out.every = p["every"] ? int(src_.integer(p["every"], "output.particles.every", 1, 100000000)) : 1;
  const YAML::Node formats = src_.require(p, "formats", "output.particles");
  if (!formats.IsSequence()) src_.fail(formats, "output.particles.formats: expected a list (ply, vtp)");
  for (size_t i = 0; i < formats.size(); ++i) {
    *src_.choice<bool*>(formats[i], "output.particles.formats", {{"ply", &out.ply}, {"vtp", &out.vtp}}) =
        true;
  }
}

void SceneReader::readSurface(const YAML::Node& node) {
  src_.allowKeys(node, {"every", "formats", "cell_size", "iso_value", "particles"}, "output.surface");
  SphSurfaceOutput& out = scene_.surface;
  if (node["every"]) {
    out.every = int(src_.integer(node["every"], "output.surface.every", 1, 100000000));
    surface_every_given_ = true;
  }
  if (const YAML::Node formats = node["formats"]) {
    if (!formats.IsSequence() || formats.size() == 0)
      src_.fail(formats, "output.surface.formats: expected a list (obj, ply)");
    out.obj = out.ply = false;
    for (size_t i = 0; i < formats.size(); ++i) {
      *src_.choice<bool*>(formats[i], "output.surface.formats", {{"obj", &out.obj}, {"ply", &out.ply}}) =
          true;
    }
  }
  if (node["cell_size"]) out.config.cell_size = src_.positive(node["cell_size"], "output.surface.cell_size");
  if (node["iso_value"]) out.config.iso_value = src_.positive(node["iso_value"], "output.surface.iso_value");
  if (const YAML::Node p = node["particles"])
    out.config.particles = src_.choice<SphSurfaceParticles>(
        p, "output.surface.particles",
        {{"fluid", SphSurfaceParticles::kFluid}, {"all", SphSurfaceParticles::kFluidAndBoundary}});
}

void SceneReader::finishSurface() {
  if (dimension_ != 3)
    src_.fail(enable_nodes_.at("surface"), "enable: 'surface' needs a 3D scene (marching cubes)");
  SphSurfaceOutput& out = scene_.surface;
  out.enabled = true;
  if (!surface_every_given_ && scene_.output.every > 0) out.every = scene_.output.every;
  out.config.smoothing_length = scene_.config.smoothing_length;
  out.config.rest_density = scene_.config.rest_density;
  out.config.num_threads = scene_.config.num_threads;
  out.config.validate();
}

}  // namespace rc::sph_scene_reading
