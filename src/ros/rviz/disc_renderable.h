// The Ogre geometry of the rviz SurfelCloud display: the disc quads of render/display/disc_quads.h in one
// static vertex buffer (36 bytes per corner, uploaded as built) with 32-bit indices, drawn with a material
// whose circular alpha mask (mirrored over the quad's (+-1, +-1) texture coordinates) cuts each quad to its
// disc by alpha rejection: no shaders, so it runs on any render system rviz runs on.
#pragma once

#include <OGRE/OgreMaterial.h>
#include <OGRE/OgreSimpleRenderable.h>

#include <vector>

#include "relaxed_connectivity/render/display/disc_quads.h"

namespace rc {

class DiscRenderable : public Ogre::SimpleRenderable {
 public:
  explicit DiscRenderable(const Ogre::MaterialPtr& material);
  ~DiscRenderable() override;
  /// Replaces the geometry (4 vertices per disc; empty: nothing drawn).
  void setVertices(const std::vector<DiscVertex>& vertices);
  size_t discs() const { return discs_; }

  Ogre::Real getSquaredViewDepth(const Ogre::Camera* camera) const override;
  Ogre::Real getBoundingRadius() const override;

 private:
  void release();
  size_t discs_ = 0;
  Ogre::Real radius_ = 0;
};

/// A material for the discs (one per display; `lighting`: shaded by rviz's light with the surfels' normals,
/// else flat colours). The mask texture is shared.
Ogre::MaterialPtr createDiscMaterial(const std::string& name, bool lighting);

}  // namespace rc
