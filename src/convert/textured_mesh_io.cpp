#include "relaxed_connectivity/convert/textured_mesh_io.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "relaxed_connectivity/render/splat/image_io.h"

#ifdef RC_HAVE_TINYGLTF
#include <tiny_gltf.h>
#endif

namespace rc {
namespace {

/// Triangles grouped by page, in index order.
std::vector<std::vector<size_t>> trianglesByPage(const TexturedMesh& mesh) {
  std::vector<std::vector<size_t>> groups(mesh.pages.size());
  for (size_t t = 0; t < mesh.mesh.triangles.size(); ++t) groups[size_t(mesh.page[t])].push_back(t);
  return groups;
}

}  // namespace

std::vector<std::string> writeTexturedObj(const std::string& obj_path, const TexturedMesh& mesh) {
  namespace fs = std::filesystem;
  const fs::path obj(obj_path);
  const std::string stem = obj.stem().string();
  const fs::path dir = obj.parent_path();
  auto beside = [&](const std::string& name) { return (dir / name).string(); };
  std::vector<std::string> files;
  const bool normals = !mesh.pages.empty() && !mesh.pages[0].normal.empty();
  const bool depths = !mesh.pages.empty() && !mesh.pages[0].depth.empty();
  // Depth pages: 16-bit grey, 0 .. 65535 spanning depth_min .. depth_max (the MTL's -mm base and gain).
  const double depth_gain = std::max(double(mesh.depth_max) - mesh.depth_min, 1e-30);
  auto writeDepth = [&](const std::string& path, const std::vector<float>& depth, uint32_t w, uint32_t h) {
    std::vector<uint16_t> values(depth.size());
    for (size_t i = 0; i < depth.size(); ++i)
      values[i] =
          uint16_t(std::lround(std::clamp((depth[i] - mesh.depth_min) / depth_gain, 0.0, 1.0) * 65535));
    writeGray16Png(path, values, w, h);
  };
  // Pages
  for (size_t k = 0; k < mesh.pages.size(); ++k) {
    const TexturePage& page = mesh.pages[k];
    files.push_back(beside(stem + "_color" + std::to_string(k) + ".png"));
    writePng(files.back(), page.color, page.width, page.height);
    if (normals) {
      files.push_back(beside(stem + "_normal" + std::to_string(k) + ".png"));
      writePng(files.back(), page.normal, page.width, page.height);
    }
    if (depths) {
      files.push_back(beside(stem + "_depth" + std::to_string(k) + ".png"));
      writeDepth(files.back(), page.depth, page.width, page.height);
    }
    for (size_t level = 0; level < page.mips.size(); ++level) {  // the atlas-pattern mip levels, beside
      const TexturePage::Mip& mip = page.mips[level];
      const std::string suffix = std::to_string(k) + "_mip" + std::to_string(level + 1) + ".png";
      files.push_back(beside(stem + "_color" + suffix));
      writePng(files.back(), mip.color, mip.width, mip.height);
      if (normals) {
        files.push_back(beside(stem + "_normal" + suffix));
        writePng(files.back(), mip.normal, mip.width, mip.height);
      }
      if (depths) {
        files.push_back(beside(stem + "_depth" + suffix));
        writeDepth(files.back(), mip.depth, mip.width, mip.height);
      }
    }
  }
  // Materials
  const std::string mtl = beside(stem + ".mtl");
  {
    std::ofstream out(mtl);
    out.precision(9);
    if (!out) throw std::runtime_error(mtl + ": cannot open for writing");
    out << "# relaxed_connectivity textured mesh: one material per texture page\n";
    for (size_t k = 0; k < mesh.pages.size(); ++k) {
      out << "newmtl page" << k << "\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nd 1\nillum 1\n";
      out << "map_Kd " << stem << "_color" << k << ".png\n";
      if (normals) out << "map_Bump -bm 1 " << stem << "_normal" << k << ".png\n";
      if (depths)
        out << "disp -mm " << mesh.depth_min << " " << depth_gain << " " << stem << "_depth" << k << ".png\n";
    }
    if (!out) throw std::runtime_error(mtl + ": write failed");
  }
  files.push_back(mtl);
  // Geometry
  std::ofstream out(obj_path);
  if (!out) throw std::runtime_error(obj_path + ": cannot open for writing");
  out << "# relaxed_connectivity textured mesh: " << mesh.mesh.vertices.size() << " vertices, "
      << mesh.mesh.triangles.size() << " triangles, " << mesh.pages.size() << " texture page(s)\n";
  out << "mtllib " << stem << ".mtl\n";
  char line[160];
  const SurfelCloud& v = mesh.mesh.vertices;
  for (size_t i = 0; i < v.size(); ++i) {
    const Vec3& p = v.positions[i];
    if (v.hasColors())
      std::snprintf(line, sizeof line, "v %.9g %.9g %.9g %.4f %.4f %.4f\n", p.x(), p.y(), p.z(),
                    v.colors[i][0] / 255.0, v.colors[i][1] / 255.0, v.colors[i][2] / 255.0);
    else
      std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", p.x(), p.y(), p.z());
    out << line;
  }
  const size_t T = mesh.mesh.triangles.size();
  for (size_t t = 0; t < T; ++t)
    for (const Eigen::Vector2f& uv : mesh.uv[t]) {
      std::snprintf(line, sizeof line, "vt %.8f %.8f\n", uv.x(), 1.0 - uv.y());
      out << line;
    }
  for (size_t t = 0; t < T; ++t) {
    const Eigen::Vector3f& n = mesh.face_normal[t];
    std::snprintf(line, sizeof line, "vn %.7f %.7f %.7f\n", n.x(), n.y(), n.z());
    out << line;
  }
  const auto groups = trianglesByPage(mesh);
  for (size_t k = 0; k < groups.size(); ++k) {
    out << "usemtl page" << k << "\n";
    for (size_t t : groups[k]) {
      const Triangle& tri = mesh.mesh.triangles[t];
      std::snprintf(line, sizeof line, "f %u/%zu/%zu %u/%zu/%zu %u/%zu/%zu\n", tri[0] + 1, 3 * t + 1, t + 1,
                    tri[1] + 1, 3 * t + 2, t + 1, tri[2] + 1, 3 * t + 3, t + 1);
      out << line;
    }
  }
  if (!out) throw std::runtime_error(obj_path + ": write failed");
  files.insert(files.begin(), obj_path);
  return files;
}

#ifdef RC_HAVE_TINYGLTF

bool glbAvailable() {
  return true;
}

void writeGlb(const std::string& path, const TexturedMesh& mesh) {
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "relaxed_connectivity rc_convert";
  model.buffers.emplace_back();
  std::vector<unsigned char>& bytes = model.buffers[0].data;
  // Appends raw data as a 4-byte aligned buffer view; returns its index.
  auto addView = [&](const void* data, size_t size, int target) {
    while (bytes.size() % 4) bytes.push_back(0);
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = bytes.size();
    view.byteLength = size;
    if (target) view.target = target;
    bytes.insert(bytes.end(), static_cast<const unsigned char*>(data),
                 static_cast<const unsigned char*>(data) + size);
    model.bufferViews.push_back(view);
    return int(model.bufferViews.size() - 1);
  };
  auto addAccessor = [&](const std::vector<float>& values, int type, int components) {
    tinygltf::Accessor a;
    a.bufferView = addView(values.data(), values.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER);
    a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    a.count = values.size() / size_t(components);
    a.type = type;
    if (type == TINYGLTF_TYPE_VEC3) {  // POSITION needs its bounds
      a.minValues.assign(3, std::numeric_limits<double>::infinity());
      a.maxValues.assign(3, -std::numeric_limits<double>::infinity());
      for (size_t i = 0; i < values.size(); ++i) {
        a.minValues[i % 3] = std::min(a.minValues[i % 3], double(values[i]));
        a.maxValues[i % 3] = std::max(a.maxValues[i % 3], double(values[i]));
      }
    }
    model.accessors.push_back(a);
    return int(model.accessors.size() - 1);
  };
  const bool normals = !mesh.pages.empty() && !mesh.pages[0].normal.empty();
  tinygltf::Sampler sampler;
  sampler.magFilter = TINYGLTF_TEXTURE_FILTER_LINEAR;
  sampler.minFilter = TINYGLTF_TEXTURE_FILTER_LINEAR;
  sampler.wrapS = sampler.wrapT = TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
  model.samplers.push_back(sampler);
  auto addTexture = [&](const std::vector<Rgba>& pixels, uint32_t w, uint32_t h, const std::string& name) {
    const std::vector<uint8_t> png = encodePng(pixels, w, h);
    tinygltf::Image image;
    image.name = name;
    image.mimeType = "image/png";
    image.bufferView = addView(png.data(), png.size(), 0);
    model.images.push_back(image);
    tinygltf::Texture texture;
    texture.sampler = 0;
    texture.source = int(model.images.size() - 1);
    model.textures.push_back(texture);
    return int(model.textures.size() - 1);
  };
  tinygltf::Mesh gmesh;
  gmesh.name = "converted";
  const auto groups = trianglesByPage(mesh);
  for (size_t k = 0; k < groups.size(); ++k) {
    const TexturePage& page = mesh.pages[k];
    tinygltf::Material material;
    material.name = "page" + std::to_string(k);
    material.pbrMetallicRoughness.metallicFactor = 0;
    material.pbrMetallicRoughness.roughnessFactor = 1;
    material.pbrMetallicRoughness.baseColorTexture.index =
        addTexture(page.color, page.width, page.height, "color" + std::to_string(k));
    if (normals)
      material.normalTexture.index =
          addTexture(page.normal, page.width, page.height, "normal" + std::to_string(k));
    model.materials.push_back(material);
    std::vector<float> position, normal, tangent, uv;
    for (size_t t : groups[k]) {
      const Triangle& tri = mesh.mesh.triangles[t];
      for (int c = 0; c < 3; ++c) {
        const Vec3& p = mesh.mesh.vertices.positions[tri[size_t(c)]];
        position.insert(position.end(), {float(p.x()), float(p.y()), float(p.z())});
        const Eigen::Vector3f& n = mesh.face_normal[t];
        normal.insert(normal.end(), {n.x(), n.y(), n.z()});
        const Eigen::Vector4f& g = mesh.tangent[t];
        tangent.insert(tangent.end(), {g.x(), g.y(), g.z(), g.w()});
        uv.insert(uv.end(), {mesh.uv[t][size_t(c)].x(), mesh.uv[t][size_t(c)].y()});
      }
    }
    tinygltf::Primitive primitive;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    primitive.material = int(k);
    primitive.attributes["POSITION"] = addAccessor(position, TINYGLTF_TYPE_VEC3, 3);
    primitive.attributes["NORMAL"] = addAccessor(normal, TINYGLTF_TYPE_VEC3, 3);
    if (normals) primitive.attributes["TANGENT"] = addAccessor(tangent, TINYGLTF_TYPE_VEC4, 4);
    primitive.attributes["TEXCOORD_0"] = addAccessor(uv, TINYGLTF_TYPE_VEC2, 2);
    gmesh.primitives.push_back(primitive);
  }
  model.meshes.push_back(gmesh);
  tinygltf::Node node;
  node.mesh = 0;
  node.name = "converted";
  node.rotation = {-std::sqrt(0.5), 0, 0, std::sqrt(0.5)};  // z-up (ROS) -> y-up (glTF)
  model.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.nodes = {0};
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToFile(&model, path, true, true, false, true))
    throw std::runtime_error(path + ": cannot write the glTF binary");
}

#else

bool glbAvailable() {
  return false;
}

void writeGlb(const std::string& path, const TexturedMesh&) {
  throw std::runtime_error(path + ": this build has no glTF writer (libtinygltf-dev)");
}

#endif

}  // namespace rc
