// Test support: an SphForceTerm that forwards to an SphElasticSolid and keeps the solid's own forces of the
// last evaluation, so tests can inspect them (momentum, the force that throws a particle) and its stats.
#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "relaxed_connectivity/sph/sph_elastic_solid.h"

namespace rc {

class RecordingSolidTerm : public SphForceTerm {
 public:
  explicit RecordingSolidTerm(std::shared_ptr<SphElasticSolid> solid) : solid_(std::move(solid)) {}
  virtual ~RecordingSolidTerm() = default;

  void beginStep(double dt) override { solid_->beginStep(dt); }
  bool implicitInStep() const override { return solid_->implicitInStep(); }
  void setNeighborSource(const SphFluidSolver* solver) override { solid_->setNeighborSource(solver); }
  double stableTimeStep(const SphParticles& particles, double cfl) const override {
    return solid_->stableTimeStep(particles, cfl);
  }
  double potentialEnergy() const override { return solid_->potentialEnergy(); }
  void addForces(const SphParticles& particles, const std::vector<Vec3>& velocities,
                 std::vector<Vec3>& forces) override {
    last.assign(particles.size(), Vec3::Zero());
    solid_->addForces(particles, velocities, last);
    for (size_t i = 0; i < last.size(); ++i) forces[i] += last[i];
    observe(particles);
  }

  const SphElasticSolid& solid() const { return *solid_; }
  std::vector<Vec3> last;  ///< the solid's forces of the last evaluation

 protected:
  /// Called after every evaluation, with `last` filled.
  virtual void observe(const SphParticles& particles) {}

 private:
  std::shared_ptr<SphElasticSolid> solid_;
};

}  // namespace rc
