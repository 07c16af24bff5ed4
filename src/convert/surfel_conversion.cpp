#include "relaxed_connectivity/convert/surfel_conversion.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "relaxed_connectivity/surface/radius_estimation.h"

namespace rc {

const char* stageName(ConversionStage stage) {
  switch (stage) {
    case ConversionStage::kReconstruction:
      return "reconstruction";
    case ConversionStage::kSimplification:
      return "simplification";
    case ConversionStage::kGeometricError:
      return "geometric error";
    case ConversionStage::kTextures:
      return "textures";
    case ConversionStage::kPacking:
      return "packing";
  }
  return "?";
}

double ConversionResult::totalSeconds() const {
  double total = 0;
  for (double s : seconds) total += s;
  return total;
}

ConversionResult convertSurfels(const SurfelCloud& input, const ConversionOptions& options,
                                const ConversionProgress& progress) {
  ConversionResult result;
  // Each stage: report 0, run with a StageProgress forwarding to `progress`, report 1, time it.
  auto run = [&](ConversionStage stage, auto&& body) {
    const auto t0 = std::chrono::steady_clock::now();
    const StageProgress report = [&](double fraction) { return !progress || progress(stage, fraction); };
    if (!report(0.0)) throw ConversionCancelled(stageName(stage));
    body(progress ? report : StageProgress());
    result.seconds[int(stage)] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!report(1.0)) throw ConversionCancelled(stageName(stage));
  };
  if (!input.hasNormals())
    throw std::invalid_argument(
        "convertSurfels: the surfels have no normals (estimate and orient them first)");
  const SurfelCloud* surfels = &input;
  SurfelCloud with_radii;
  if (!input.hasRadii() && !input.hasAxes()) {
    with_radii = input;
    with_radii.removeNonFinite();
    if (with_radii.size() != input.size())
      throw std::invalid_argument("convertSurfels: " + std::to_string(input.size() - with_radii.size()) +
                                  " surfels have non-finite positions or normals");
    if (with_radii.size() < 4)
      throw std::invalid_argument("convertSurfels: " + std::to_string(with_radii.size()) +
                                  " surfels are too few for a surface");
    estimateRadii(with_radii, RadiusEstimationConfig());
    result.radii_estimated = with_radii.size();
    surfels = &with_radii;
  }
  TriangleMesh reconstructed, simplified;
  run(ConversionStage::kReconstruction, [&](const StageProgress& p) {
    reconstructed = reconstructSurface(*surfels, options.reconstruction, &result.reconstruction, p);
  });
  run(ConversionStage::kSimplification, [&](const StageProgress& p) {
    simplified = simplifyMesh(reconstructed, options.simplification, &result.simplification, p);
  });
  reconstructed = TriangleMesh();
  if (options.measure_geometric_error)
    run(ConversionStage::kGeometricError,
        [&](const StageProgress&) { result.geometric_error = geometricError(simplified, *surfels); });
  std::vector<TrianglePatches> patches;
  run(ConversionStage::kTextures, [&](const StageProgress& p) {
    TextureOptions texture = options.texture;
    texture.border = options.atlas.border;  // the patches are the packing's masks
    patches = computeTexturePatches(simplified, *surfels, texture, &result.texture, p);
  });
  double area_sum = 0;
  for (const TrianglePatches& p : patches) {
    const double area = 0.5 * p.frame.base * p.frame.height;
    area_sum += area;
    result.color_error_max = std::max(result.color_error_max, p.color.error);
    result.color_error_mean += area * p.color.error;
    result.normal_error_max = std::max(result.normal_error_max, p.normal.error);
    result.normal_error_mean += area * p.normal.error;
    result.depth_error_max = std::max(result.depth_error_max, p.depth.error);
    result.depth_error_mean += area * p.depth.error;
  }
  if (area_sum > 0) {
    result.color_error_mean /= area_sum;
    result.normal_error_mean /= area_sum;
    result.depth_error_mean /= area_sum;
  }
  run(ConversionStage::kPacking,
      [&](const StageProgress&) { result.textured = buildTexturedMesh(simplified, patches, options.atlas); });
  return result;
}

}  // namespace rc
