// A flat 1 m square cloth of two triangles at z = 0, centred on the origin: the mesh the control tests aim at.
#pragma once

#include "tachi/viewer/render.hpp"

namespace tachi::viewer::test {
inline Mesh square() {
  Mesh mesh;
  mesh.positions = {{-0.5F, 0.5F, 0.0F}, {0.5F, 0.5F, 0.0F}, {-0.5F, -0.5F, 0.0F}, {0.5F, -0.5F, 0.0F}};
  mesh.triangles = {{0, 1, 2}, {1, 3, 2}};
  return mesh;
}
}  // namespace tachi::viewer::test
