#include "relaxed_connectivity/ros/rviz/disc_renderable.h"

#include <OGRE/OgreHardwareBufferManager.h>
#include <OGRE/OgreImage.h>
#include <OGRE/OgreMaterialManager.h>
#include <OGRE/OgreResourceGroupManager.h>
#include <OGRE/OgreTechnique.h>
#include <OGRE/OgreTextureManager.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace rc {
namespace {

constexpr int kMaskSize = 64;

/// A quarter disc (texel (s, t) opaque where s^2 + t^2 <= 1, white): mirrored addressing over the quad's
/// texture coordinates in [-1, 1] makes the whole disc.
const Ogre::TexturePtr& discMask() {
  static Ogre::TexturePtr mask;
  if (mask) return mask;
  static std::vector<uint8_t> rgba(kMaskSize * kMaskSize * 4);
  for (int t = 0; t < kMaskSize; ++t)
    for (int s = 0; s < kMaskSize; ++s) {
      const double u = (s + 0.5) / kMaskSize, v = (t + 0.5) / kMaskSize;
      uint8_t* p = &rgba[(t * kMaskSize + s) * 4];
      p[0] = p[1] = p[2] = 255;
      p[3] = u * u + v * v <= 1.0 ? 255 : 0;
    }
  Ogre::Image image;
  image.loadDynamicImage(rgba.data(), kMaskSize, kMaskSize, 1, Ogre::PF_BYTE_RGBA);
  mask = Ogre::TextureManager::getSingleton().loadImage("relaxed_connectivity_disc_mask", Ogre::RGN_DEFAULT,
                                                        image, Ogre::TEX_TYPE_2D, 0);
  return mask;
}

}  // namespace

Ogre::MaterialPtr createDiscMaterial(const std::string& name, bool lighting) {
  Ogre::MaterialPtr material = Ogre::MaterialManager::getSingleton().create(name, Ogre::RGN_DEFAULT);
  Ogre::Pass* pass = material->getTechnique(0)->getPass(0);
  pass->setLightingEnabled(lighting);
  pass->setVertexColourTracking(Ogre::TVC_AMBIENT | Ogre::TVC_DIFFUSE);
  pass->setCullingMode(Ogre::CULL_NONE);  // two-sided: open scans and sheets
  pass->setAlphaRejectSettings(Ogre::CMPF_GREATER_EQUAL, 128);
  Ogre::TextureUnitState* mask = pass->createTextureUnitState();
  mask->setTexture(discMask());
  mask->setTextureAddressingMode(Ogre::TextureUnitState::TAM_MIRROR);
  mask->setTextureFiltering(Ogre::TFO_NONE);  // crisp disc edges (the mask is sampled, not blended)
  return material;
}

DiscRenderable::DiscRenderable(const Ogre::MaterialPtr& material) {
  setMaterial(material);
  mRenderOp.operationType = Ogre::RenderOperation::OT_TRIANGLE_LIST;
  mRenderOp.useIndexes = true;
  mRenderOp.vertexData = nullptr;
  mRenderOp.indexData = nullptr;
  setBoundingBox(Ogre::AxisAlignedBox::BOX_NULL);
}

DiscRenderable::~DiscRenderable() {
  release();
}

void DiscRenderable::release() {
  delete mRenderOp.vertexData;
  delete mRenderOp.indexData;
  mRenderOp.vertexData = nullptr;
  mRenderOp.indexData = nullptr;
  discs_ = 0;
}

void DiscRenderable::setVertices(const std::vector<DiscVertex>& vertices) {
  release();
  const size_t count = vertices.size();
  if (count == 0) {
    setBoundingBox(Ogre::AxisAlignedBox::BOX_NULL);
    radius_ = 0;
    return;
  }
  discs_ = count / 4;
  auto& buffers = Ogre::HardwareBufferManager::getSingleton();
  mRenderOp.vertexData = new Ogre::VertexData();
  Ogre::VertexDeclaration* declaration = mRenderOp.vertexData->vertexDeclaration;
  declaration->addElement(0, offsetof(DiscVertex, position), Ogre::VET_FLOAT3, Ogre::VES_POSITION);
  declaration->addElement(0, offsetof(DiscVertex, normal), Ogre::VET_FLOAT3, Ogre::VES_NORMAL);
  declaration->addElement(0, offsetof(DiscVertex, colour), Ogre::VET_UBYTE4_NORM, Ogre::VES_DIFFUSE);
  declaration->addElement(0, offsetof(DiscVertex, uv), Ogre::VET_FLOAT2, Ogre::VES_TEXTURE_COORDINATES, 0);
  Ogre::HardwareVertexBufferSharedPtr vertex_buffer =
      buffers.createVertexBuffer(sizeof(DiscVertex), count, Ogre::HardwareBuffer::HBU_STATIC_WRITE_ONLY);
  vertex_buffer->writeData(0, count * sizeof(DiscVertex), vertices.data(), true);
  mRenderOp.vertexData->vertexBufferBinding->setBinding(0, vertex_buffer);
  mRenderOp.vertexData->vertexStart = 0;
  mRenderOp.vertexData->vertexCount = count;

  Ogre::HardwareIndexBufferSharedPtr index_buffer = buffers.createIndexBuffer(
      Ogre::HardwareIndexBuffer::IT_32BIT, 6 * discs_, Ogre::HardwareBuffer::HBU_STATIC_WRITE_ONLY);
  std::vector<uint32_t> indices(6 * discs_);
  for (size_t k = 0; k < discs_; ++k) {
    const uint32_t v = uint32_t(4 * k);
    const uint32_t quad[6] = {v, v + 1, v + 2, v, v + 2, v + 3};
    std::memcpy(&indices[6 * k], quad, sizeof(quad));
  }
  index_buffer->writeData(0, indices.size() * sizeof(uint32_t), indices.data(), true);
  mRenderOp.indexData = new Ogre::IndexData();
  mRenderOp.indexData->indexBuffer = index_buffer;
  mRenderOp.indexData->indexStart = 0;
  mRenderOp.indexData->indexCount = indices.size();

  Ogre::Vector3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (const DiscVertex& v : vertices) {
    const Ogre::Vector3 p(v.position[0], v.position[1], v.position[2]);
    lo.makeFloor(p);
    hi.makeCeil(p);
  }
  setBoundingBox(Ogre::AxisAlignedBox(lo, hi));
  radius_ = std::max(lo.length(), hi.length());
}

Ogre::Real DiscRenderable::getSquaredViewDepth(const Ogre::Camera* camera) const {
  return getParentNode() ? getParentNode()->getSquaredViewDepth(camera) : 0;
}

Ogre::Real DiscRenderable::getBoundingRadius() const {
  return radius_;
}

}  // namespace rc
