// The exact classification of first contacts (geometry/exact_contact.h) and the ill-conditioned
// marker (accel/exact/contact_classes.h) on configurations whose classes are known: interior
// and shared-edge crossings, silhouette edges and vertices, rays in a face's plane, starts on a
// surface, tangent spheres, near-misses by an ulp.
#include <gtest/gtest.h>

#include <cmath>

#include "accel/common/ray_sets.h"
#include "accel/exact/contact_classes.h"
#include "geometry/exact_contact.h"
#include "rays/feature_rays.h"
#include "scene/scene_spec.h"

namespace raylab {
namespace {

std::shared_ptr<Scene> mesh_scene(const std::vector<std::array<Vec3f, 3>>& tris) {
  auto s = std::make_shared<Scene>();
  s->spec = "hand-made";
  for (const auto& t : tris) {
    const auto base = static_cast<std::uint32_t>(s->mesh.vertices.size());
    s->mesh.vertices.insert(s->mesh.vertices.end(), t.begin(), t.end());
    s->mesh.triangles.push_back({base, base + 1, base + 2});
  }
  return s;
}

RayContact classify(const std::shared_ptr<const Scene>& scene, const Ray& ray) {
  return classify_contacts(scene, {ray}, 1).front();
}

// A roof: two faces meeting at the ridge y = 0, z = 1 (a convex edge), seen from above and
// from the side.
const std::vector<std::array<Vec3f, 3>> kRoof = {
    {Vec3f(0, -1, 0), Vec3f(2, -1, 0), Vec3f(0, 0, 1)}, {Vec3f(2, -1, 0), Vec3f(2, 0, 1), Vec3f(0, 0, 1)},
    {Vec3f(0, 0, 1), Vec3f(2, 0, 1), Vec3f(0, 1, 0)},   {Vec3f(2, 0, 1), Vec3f(2, 1, 0), Vec3f(0, 1, 0)}};

TEST(ContactClasses, CrossingTouchingOnSurfaceAndNone) {
  const auto roof = mesh_scene(kRoof);
  // Straight down through the ridge (the edge shared by two faces on either side): a crossing.
  EXPECT_EQ(classify(roof, {{1.0f, 0.0f, 3.0f}, {0, 0, -1}}).contact, Contact::crossing);
  // Into a face's interior: a crossing, well-conditioned.
  const RayContact interior = classify(roof, {{0.5f, -0.5f, 3.0f}, {0, 0, -1}});
  EXPECT_EQ(interior.contact, Contact::crossing);
  EXPECT_FALSE(interior.ill_conditioned);
  // Horizontally along x just on the ridge line: both faces lie below the ray: touching.
  const RayContact ridge = classify(roof, {{-1.0f, 0.0f, 1.0f}, {1, 0, 0}});
  EXPECT_EQ(ridge.contact, Contact::touching);
  EXPECT_TRUE(ridge.ill_conditioned);
  // Across the ridge, horizontally in y: touches the ridge at (1, 0, 1) with both faces below.
  EXPECT_EQ(classify(roof, {{1.0f, -3.0f, 1.0f}, {0, 1, 0}}).contact, Contact::touching);
  // Starting on a face: on_surface; and a ray that misses everything: none, well-conditioned.
  EXPECT_EQ(classify(roof, {{0.5f, -0.5f, 0.5f}, {0, 0, 1}}).contact, Contact::on_surface);
  const RayContact miss = classify(roof, {{5.0f, 5.0f, 5.0f}, {0, 0, 1}});
  EXPECT_EQ(miss.contact, Contact::none);
  EXPECT_FALSE(miss.ill_conditioned);
}

TEST(ContactClasses, VerticesInsideAndOutsideTheTangentCone) {
  // A square pyramid (closed by its base): the apex seen from above is a crossing, the apex
  // grazed horizontally is touching.
  const Vec3f apex(0, 0, 1), a(-1, -1, 0), b(1, -1, 0), c(1, 1, 0), d(-1, 1, 0);
  const auto pyramid = mesh_scene({{a, b, apex}, {b, c, apex}, {c, d, apex}, {d, a, apex}, {a, c, b}, {a, d, c}});
  const RayContact down = classify(pyramid, {{0.0f, 0.0f, 3.0f}, {0, 0, -1}});
  EXPECT_EQ(down.contact, Contact::crossing);
  EXPECT_FALSE(down.ill_conditioned) << "a crossing inside the tangent cone moves continuously";
  const RayContact side = classify(pyramid, {{-3.0f, 0.0f, 1.0f}, {1, 0, 0}});
  EXPECT_EQ(side.contact, Contact::touching);
  EXPECT_TRUE(side.ill_conditioned);
}

TEST(ContactClasses, NearMissesOfASilhouetteAreIllConditioned) {
  const auto roof = mesh_scene(kRoof);
  // One ulp above the ridge, horizontally: no contact, but the answer turns on that ulp.
  const RayContact above = classify(roof, {{1.0f, -3.0f, std::nextafter(1.0f, 2.0f)}, {0, 1, 0}});
  EXPECT_EQ(above.contact, Contact::none);
  EXPECT_TRUE(above.ill_conditioned);
  // One ulp below: it crosses the roof twice near the ridge; also ill-conditioned.
  const RayContact below = classify(roof, {{1.0f, -3.0f, std::nextafter(1.0f, 0.0f)}, {0, 1, 0}});
  EXPECT_EQ(below.contact, Contact::crossing);
  EXPECT_TRUE(below.ill_conditioned);
  // Well above: none, well-conditioned.
  EXPECT_FALSE(classify(roof, {{1.0f, -3.0f, 1.5f}, {0, 1, 0}}).ill_conditioned);
}

TEST(ContactClasses, RaysInAFacePlaneAndSpheres) {
  const auto roof = mesh_scene(kRoof);
  // In the plane of the first face, along its slope: the contact is a segment of the face.
  EXPECT_EQ(classify(roof, {{1.0f, -2.0f, -1.0f}, {0, 1, 1}}).contact, Contact::touching);
  auto spheres = std::make_shared<Scene>();
  spheres->spec = "spheres";
  spheres->spheres = {{{0, 0, 0}, 1.0f}};
  EXPECT_EQ(classify(spheres, {{1.0f, 0.0f, -5.0f}, {0, 0, 1}}).contact, Contact::touching);  // tangent
  const RayContact through = classify(spheres, {{0.5f, 0.0f, -5.0f}, {0, 0, 1}});
  EXPECT_EQ(through.contact, Contact::crossing);
  EXPECT_FALSE(through.ill_conditioned);
  EXPECT_EQ(classify(spheres, {{0.0f, 0.0f, 0.0f}, {0, 0, 1}}).contact, Contact::crossing);  // from inside, out
}

// The generators: touching rays touch (exactly), feature rays on closed meshes cross and are
// well-conditioned, grazing rays are mostly ill-conditioned.
TEST(ContactClasses, GeneratorsMakeTheClassesTheyPromise) {
  const auto scene = make_scene("cgal:couplingdown");
  ASSERT_TRUE(describe(*scene).closed);
  const auto touching = classify_contacts(scene, make_ray_set("touching:256", scene));
  std::size_t touch = 0;
  for (const auto& c : touching) touch += c.contact == Contact::touching;
  EXPECT_GE(touch, touching.size() * 9 / 10) << "a touching ray is occluded only by another part of the mesh";
  const auto vertices = classify_contacts(scene, make_ray_set("vertices:256", scene));
  std::size_t clean = 0;
  for (const auto& c : vertices) clean += c.contact == Contact::crossing && !c.ill_conditioned;
  EXPECT_GE(clean, vertices.size() * 9 / 10);
  const auto grazing = classify_contacts(scene, make_ray_set("grazing:256", scene));
  std::size_t ill = 0;
  for (const auto& c : grazing) ill += c.ill_conditioned;
  EXPECT_GE(ill, grazing.size() / 2);
}

// Vertex-aimed rays meet their vertex exactly: on a soup of lone triangles each such contact
// is a touch, so a generator whose rays merely pass near the vertex (off by a rounding) fails.
TEST(ContactClasses, VertexAimedRaysMeetTheirVertexExactly) {
  const auto soup = make_scene("soup:n=200");
  const auto classes = classify_contacts(soup, make_ray_set("vertices:256", soup));
  std::size_t touch = 0;
  for (const auto& c : classes) touch += c.contact == Contact::touching;
  EXPECT_GE(touch, classes.size() * 9 / 10);
}

TEST(ContactClasses, RayExactlyThroughAPointPassesThroughItExactly) {
  const Vec3f p(1e4f + 0.125f, -3.0f, 0.7f);
  Ray ray;
  ASSERT_TRUE(ray_exactly_through(p, {0.3, -0.2, 0.9}, 0.5, ray));
  // o + 2^k·d = p for some k: every coordinate of p - o is the same multiple of d.
  const double k = (double(p.z) - ray.org.z) / ray.dir.z;
  for (int a = 0; a < 3; ++a) EXPECT_EQ(double(ray.org[a]) + k * ray.dir[a], double(p[a]));
  EXPECT_EQ(std::exp2(std::round(std::log2(k))), k);
}

}  // namespace
}  // namespace raylab
