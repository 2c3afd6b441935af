// A consumer of the installed package: builds an accelerator through the factory and traces one
// ray. Exits 0 only when the ray hits the triangle at t = 1.
#include <raylab/accel/common/accel_factory.h>

#include <cstdio>

int main() {
  auto scene = std::make_shared<raylab::Scene>();
  scene->mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  scene->mesh.triangles = {{0, 1, 2}};
  const auto accel = raylab::make_accelerator("brute", scene);
  raylab::Ray ray{{0.25f, 0.25f, 1.0f}, {0, 0, -1}};
  raylab::Hit hit;
  const bool found = accel->intersect(ray, hit);
  std::printf("hit=%d t=%g\n", found, hit.t);
  return found && hit.t == 1.0f ? 0 : 1;
}
