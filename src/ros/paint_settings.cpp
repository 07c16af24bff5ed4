#include "relaxed_connectivity/ros/paint_settings.h"

namespace rc {

void applyPaintReconfigure(const relaxed_connectivity::PaintConfig& config, BrushPreset* preset,
                           PaintType* paint) {
  preset->spring_stiffness = config.spring_stiffness;
  preset->damping = config.damping;
  preset->mass = config.mass;
  preset->friction = config.friction;
  preset->penalty_stiffness = config.penalty_stiffness;
  preset->integrator = config.integrator == 1 ? BrushIntegrator::kImplicitEuler : BrushIntegrator::kVerlet;
  preset->time_step = config.time_step;
  preset->split_angle_deg = config.split_angle_deg;
  preset->collision_neighbors = config.collision_neighbors;
  if (!paint) return;
  paint->optical_density = config.optical_density;
  paint->transfer_to_surface = config.transfer_to_surface;
  paint->transfer_to_brush = config.transfer_to_brush;
  paint->drying_rate = config.drying_rate;
  paint->diffusion = config.diffusion;
}

void writePaintReconfigure(const BrushPreset& preset, const PaintType* paint,
                           relaxed_connectivity::PaintConfig* config) {
  config->spring_stiffness = preset.spring_stiffness;
  config->damping = preset.damping;
  config->mass = preset.mass;
  config->friction = preset.friction;
  config->penalty_stiffness = preset.penalty_stiffness;
  config->integrator = preset.integrator == BrushIntegrator::kImplicitEuler ? 1 : 0;
  config->time_step = preset.time_step;
  config->split_angle_deg = preset.split_angle_deg;
  config->collision_neighbors = preset.collision_neighbors;
  if (!paint) return;
  config->optical_density = paint->optical_density;
  config->transfer_to_surface = paint->transfer_to_surface;
  config->transfer_to_brush = paint->transfer_to_brush;
  config->drying_rate = paint->drying_rate;
  config->diffusion = paint->diffusion;
}

bool sameBrushSettings(const BrushPreset& a, const BrushPreset& b) {
  return a.spring_stiffness == b.spring_stiffness && a.damping == b.damping && a.mass == b.mass &&
         a.friction == b.friction && a.penalty_stiffness == b.penalty_stiffness &&
         a.integrator == b.integrator && a.time_step == b.time_step &&
         a.split_angle_deg == b.split_angle_deg && a.collision_neighbors == b.collision_neighbors;
}

bool samePaintSettings(const PaintType& a, const PaintType& b) {
  return a.optical_density == b.optical_density && a.transfer_to_surface == b.transfer_to_surface &&
         a.transfer_to_brush == b.transfer_to_brush && a.drying_rate == b.drying_rate &&
         a.diffusion == b.diffusion;
}

}  // namespace rc
