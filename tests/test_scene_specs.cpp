// Scene specs: every procedural scene with small parameters, mesh specs, and spec errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "accel/common/tracer.h"
#include "geometry/input_error.h"
#include "scene/procedural.h"
#include "scene/scene.h"
#include "scene/scene_spec.h"

using namespace raylab;

namespace {

const std::string kData = RAYLAB_TEST_DATA;

/// Six times the signed volume enclosed by a closed mesh (positive when it faces outward).
double signed_volume6(const TriangleMesh& m) {
  double v = 0;
  for (std::size_t t = 0; t < m.size(); ++t)
    v += dot(Vec3d(m.vertex(t, 0)), cross(Vec3d(m.vertex(t, 1)), Vec3d(m.vertex(t, 2))));
  return v;
}

bool inside(const Bounds3f& inner, const Bounds3f& outer) { return outer.contains(inner.lo) && outer.contains(inner.hi); }

}  // namespace

TEST(SceneSpecs, SphereIsClosedAndOutward) {
  for (const char* spec : {"sphere:n=8", "sphere:n=100", "sphere", "sphere:n=20000,radius=3"}) {
    SCOPED_TRACE(spec);
    const auto s = make_scene(spec);
    EXPECT_EQ(s->spec, spec);
    const SceneInfo info = describe(*s);
    EXPECT_TRUE(info.closed);
    EXPECT_EQ(info.degenerate_triangles, 0u);
    EXPECT_GT(signed_volume6(s->mesh), 0.0);
  }
  EXPECT_EQ(make_scene("sphere:n=8")->triangle_count(), 8u);
  const auto s = make_scene("sphere:n=5000");
  EXPECT_NEAR(static_cast<double>(s->triangle_count()), 5000.0, 200.0);
  EXPECT_NEAR(s->bounds().hi.y, 1.0f, 1e-6f);
  EXPECT_NEAR(s->bounds().lo.y, -1.0f, 1e-6f);
}

TEST(SceneSpecs, Sphereflake) {
  const auto s = make_scene("sphereflake:depth=2");
  EXPECT_EQ(s->spheres.size(), 91u);
  EXPECT_EQ(s->triangle_count(), 0u);
  EXPECT_TRUE(describe(*s).closed);
  EXPECT_EQ(make_scene("sphereflake:depth=0")->spheres.size(), 1u);
  EXPECT_EQ(make_scene("sphereflake")->spheres.size(), 7381u);
  // Children touch their parent and have a third of its radius.
  EXPECT_FLOAT_EQ(s->spheres[1].radius, 1.0f / 3.0f);
  EXPECT_NEAR(length(s->spheres[1].center - s->spheres[0].center), 4.0 / 3.0, 1e-6);
  const auto t = make_scene("sphereflake:depth=2,as=triangles,tess=4");
  EXPECT_EQ(t->triangle_count(), 91u * 2 * 8 * 3);
  EXPECT_TRUE(t->spheres.empty());
  EXPECT_TRUE(inside(t->bounds(), s->bounds()));
}

TEST(SceneSpecs, StadiumHoldsTheObjectAtItsScale) {
  const auto obj = make_scene("sphereflake:depth=1");
  const auto s = make_scene("stadium:object=(sphereflake:depth=1),ratio=100");
  EXPECT_EQ(s->spheres.size(), 10u);
  EXPECT_EQ(s->triangle_count(), 96u * (1 + 4 * 8));
  const double obj_diag = length(Vec3d(obj->bounds().diagonal()));
  const double diag = length(Vec3d(s->bounds().diagonal()));
  EXPECT_GT(diag, 100 * obj_diag);
  EXPECT_LT(diag, 200 * obj_diag);
  // The object keeps its coordinates.
  EXPECT_EQ(s->spheres[0].center, obj->spheres[0].center);
  EXPECT_EQ(make_scene("stadium:ratio=10,segments=16,tiers=2")->triangle_count(), make_scene("sphere:n=5000")->triangle_count() + 16u * 9);
}

TEST(SceneSpecs, Grass) {
  const auto s = make_scene("grass:blades=200,height=0.1");
  EXPECT_EQ(s->triangle_count(), 600u);
  const Bounds3f b = s->bounds();
  EXPECT_GE(b.lo.y, 0.0f);
  EXPECT_LE(b.hi.y, 0.1f + 1e-6f);
  EXPECT_GT(b.lo.x, -0.1f);
  EXPECT_LT(b.hi.x, 1.1f);
  EXPECT_EQ(describe(*s).degenerate_triangles, 0u);
}

TEST(SceneSpecs, Walls) {
  const auto s = make_scene("walls:n=10,angle=0");
  EXPECT_EQ(s->triangle_count(), 120u);
  EXPECT_TRUE(describe(*s).closed);
  const auto r = make_scene("walls:n=10,angle=45");
  EXPECT_TRUE(describe(*r).closed);
  EXPECT_GT(signed_volume6(r->mesh), 0.0);
  EXPECT_NEAR(r->bounds().hi.y, 1.0f, 1e-6f);
  EXPECT_NEAR(r->bounds().lo.y, 0.0f, 1e-6f);
}

TEST(SceneSpecs, RoomEnclosesTheObjectAndMakesBouncesHit) {
  const auto object = make_scene("sphere:n=200");
  const auto s = make_scene("room:of=(sphere:n=200),margin=1,window=0.8");
  EXPECT_EQ(s->triangle_count(), object->triangle_count() + 3 * (2 + 8));
  const Bounds3f ob = object->bounds(), rb = s->bounds();
  const float grow = ob.hi.x - ob.lo.x;  // margin 1 times the largest extent (the sphere's diameter)
  EXPECT_NEAR(rb.lo.x, ob.lo.x - grow, 1e-5f);
  EXPECT_NEAR(rb.hi.z, ob.hi.z + grow, 1e-5f);
  // The camera sees the object through the windows; bounces from what it sees (frames' outsides
  // included) hit a wall or the object far more often than the bare object's do.
  const auto embree = make_accelerator("embree-robust", s);
  const auto primary = make_ray_set("primary:4096", s);
  const TraceResult seen = trace_rays(*embree, primary, TraceOptions{1, false, false});
  EXPECT_TRUE(std::any_of(seen.hits.begin(), seen.hits.end(),
                          [&](const Hit& h) { return h.prim < object->triangle_count(); }));
  const auto diffuse = make_ray_set("diffuse:4096", s);
  const TraceResult bounced = trace_rays(*embree, diffuse, TraceOptions{1, false, false});
  EXPECT_GT(bounced.hit_count, diffuse.size() * 3 / 10);
  // The same diffuse rays hit far less often with the room taken away.
  const auto alone = make_accelerator("embree-robust", object);
  EXPECT_LT(2 * trace_rays(*alone, diffuse, TraceOptions{1, false, false}).hit_count, bounced.hit_count);
}

TEST(SceneSpecs, ClosedRoomSeenFromInsideHitsEveryBounce) {
  const auto object = make_scene("sphere:n=200");
  const auto s = make_scene("room:of=(sphere:n=200),window=0");
  EXPECT_EQ(s->triangle_count(), object->triangle_count() + 12);
  EXPECT_TRUE(describe(*s).closed);
  const auto embree = make_accelerator("embree-robust", s);
  const auto primary = make_ray_set("primary:4096,camera=inside", s);
  const TraceResult seen = trace_rays(*embree, primary, TraceOptions{1, false, false});
  EXPECT_EQ(seen.hit_count, primary.size());
  EXPECT_TRUE(std::any_of(seen.hits.begin(), seen.hits.end(),
                          [&](const Hit& h) { return h.prim < object->triangle_count(); }));
  const auto diffuse = make_ray_set("diffuse:4096,camera=inside", s);
  EXPECT_EQ(trace_rays(*embree, diffuse, TraceOptions{1, false, false}).hit_count, diffuse.size());
  // From outside, the closed room hides the object: every primary hit is on a wall.
  const TraceResult outside =
      trace_rays(*embree, make_ray_set("primary:1024", s), TraceOptions{1, false, false});
  EXPECT_TRUE(std::none_of(outside.hits.begin(), outside.hits.end(), [&](const Hit& h) {
    return h.valid() && h.prim < object->triangle_count();
  }));
}

TEST(SceneSpecs, SoupIsDeterministic) {
  const auto a = make_scene("soup:n=1000");
  const auto b = make_scene("soup:n=1000,seed=1");
  const auto c = make_scene("soup:n=1000,seed=2");
  EXPECT_EQ(a->triangle_count(), 1000u);
  EXPECT_TRUE(inside(a->bounds(), Bounds3f(Vec3f(0.0f), Vec3f(1.0f))));
  EXPECT_TRUE(a->mesh.vertices == b->mesh.vertices);
  EXPECT_FALSE(a->mesh.vertices == c->mesh.vertices);
}

TEST(SceneSpecs, InstancesStoreOnlyTransforms) {
  const auto s = make_scene("instances:of=(sphere:n=100),count=27");
  ASSERT_TRUE(s->instanced());
  EXPECT_EQ(s->instances.size(), 27u);
  const SceneInfo info = describe(*s);
  EXPECT_EQ(info.instances, 27u);
  EXPECT_EQ(info.triangles, 27u * s->bases.at(0)->triangle_count());
  EXPECT_TRUE(info.closed);
  EXPECT_DOUBLE_EQ(info.primitives, 27.0 * static_cast<double>(s->bases.at(0)->triangle_count()));
  EXPECT_THROW(make_scene("instances:of=(instances:of=(sphere:n=100),count=2),count=2"), InputError);
  EXPECT_THROW(make_scene("instances:of=(sphere:n=100),count=1000000001"), InputError);
}

// `transformed` places a scene under a similarity: far from the origin, tiny or huge, rotated.
TEST(SceneSpecs, TransformedMovesRotatesAndScales) {
  const auto base = make_scene("sphere:n=200");
  const auto far = make_scene("transformed:of=(sphere:n=200),translate=1e6:-2e5:0");
  ASSERT_EQ(far->mesh.size(), base->mesh.size());
  EXPECT_NEAR(far->bounds().center().x, 1e6, 1.0);
  EXPECT_NEAR(far->bounds().center().y, -2e5, 1.0);
  EXPECT_TRUE(describe(*far).closed);
  const auto tiny = make_scene("transformed:of=(sphere:n=200),scale=1e-6,rotate=x:90");
  EXPECT_NEAR(tiny->bounds().diagonal().x, 2e-6, 1e-9);
  const auto turned = make_scene("transformed:of=(sphere:n=200),rotate=0;0;1:90");
  const Vec3f v = base->mesh.vertices[5], w = turned->mesh.vertices[5];
  EXPECT_NEAR(w.x, -v.y, 1e-6);
  EXPECT_NEAR(w.y, v.x, 1e-6);
  const auto flake = make_scene("transformed:of=(sphereflake:depth=1),scale=2,translate=1e3:0:0");
  EXPECT_FLOAT_EQ(flake->spheres.front().radius, 2.0f * make_scene("sphereflake:depth=1")->spheres.front().radius);
  const auto inst = make_scene("transformed:of=(instances:of=(sphere:n=100),count=8),translate=0:1e4:0");
  ASSERT_TRUE(inst->instanced());
  EXPECT_GT(inst->bounds().lo.y, 9e3f);
  for (const char* bad : {"transformed:of=sphere,rotate=w:3", "transformed:of=sphere,rotate=0;0;0:3",
                          "transformed:of=sphere,translate=1:2", "transformed:of=sphere,scale=0",
                          "transformed:of=(sphere:radius=1e10),scale=1e30", "transformed:of=sphere,spin=3"})
    EXPECT_THROW(make_scene(bad), InputError) << bad;
}

TEST(SceneSpecs, Subdivided) {
  const auto base = make_scene("sphere:n=100");
  const auto s = make_scene("subdivided:of=(sphere:n=100),levels=2");
  EXPECT_EQ(s->triangle_count(), 16 * base->triangle_count());
  EXPECT_TRUE(describe(*s).closed);
  EXPECT_THROW(make_scene("subdivided:of=(sphereflake:depth=1),levels=1"), InputError);
  EXPECT_THROW(make_scene("subdivided:of=(soup:n=100000),levels=8"), InputError);  // > 2^27 triangles
}

TEST(SceneSpecs, Decimated) {
  const auto s = make_scene("decimated:of=(sphere:n=5000),faces=500");
  EXPECT_LE(s->triangle_count(), 500u);
  EXPECT_GT(s->triangle_count(), 100u);
  EXPECT_TRUE(describe(*s).closed);
}

TEST(SceneSpecs, MeshFiles) {
  const std::string path = kData + "/meshes/cube_quads.off";
  EXPECT_EQ(make_scene(path)->triangle_count(), 12u);
  EXPECT_EQ(make_scene("file:" + path)->triangle_count(), 12u);
  EXPECT_EQ(make_scene("file:(" + path + ")")->triangle_count(), 12u);
  EXPECT_EQ(make_scene("subdivided:of=" + path + ",levels=1")->triangle_count(), 48u);
  const auto bunny = make_scene("cgal:bunny00");
  EXPECT_GT(bunny->triangle_count(), 30000u);
  EXPECT_EQ(bunny->spec, "cgal:bunny00");
}

TEST(SceneSpecs, ErrorsAreInputErrors) {
  for (const char* spec : {"", "teapot", "teapot:n=3", "sphere:m=4", "sphere:n=abc", "sphere:n=3", "sphere:n=1e99",
                           "sphereflake:depth=8", "sphereflake:as=cubes", "stadium:object=(sphere:n=100", "grass:blades=0",
                           "walls:angle=nan", "soup:n=-1", "cgal:no_such_mesh", "cgal", "cgal:a,b", "cgal:bunny00,x=1",
                           "file:/no/such/file.off", "/no/such/file.ply", "instances:of=(sphere:n=100),count=0",
                           "stadium:object=(sphere:n=100),ratio=0", "sphere:5", "room:margin=0",
                           "room:of=(sphere:n=100),margin=nan", "room:window=1", "room:window=0.01",
                           "room:of=(instances:of=(sphere:n=100),count=2)"}) {
    SCOPED_TRACE(spec);
    EXPECT_THROW(make_scene(spec), InputError);
  }
}

TEST(SceneSpecs, UnknownKindListsTheValidOnes) {
  try {
    make_scene("teapot:n=3");
    FAIL();
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("teapot"), std::string::npos);
    EXPECT_NE(msg.find("sphereflake"), std::string::npos);
  }
  try {
    make_scene("sphere:m=4");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("radius"), std::string::npos) << e.what();
  }
}

TEST(SceneSpecs, KindsAreDocumented) {
  const auto& kinds = scene_kinds();
  for (const char* name : {"cgal", "file", "sphere", "sphereflake", "stadium", "grass", "walls", "room", "soup", "dust",
                           "needles", "fan", "row", "subdivided", "decimated", "instances"}) {
    const auto it = std::find_if(kinds.begin(), kinds.end(), [&](const SceneKindDoc& k) { return k.name == name; });
    ASSERT_NE(it, kinds.end()) << name;
    EXPECT_FALSE(it->summary.empty());
    for (const auto& p : it->params) EXPECT_FALSE(p.description.empty()) << name << ":" << p.key;
  }
}

TEST(SceneSpecs, UvSphereCounts) {
  const TriangleMesh m = uv_sphere(Vec3f(1, 2, 3), 0.5f, 5, 7);
  EXPECT_EQ(m.size(), 2u * 7 * 4);
  EXPECT_EQ(m.vertices.size(), 2u + 4 * 7);
  Scene s;
  s.mesh = m;
  EXPECT_TRUE(describe(s).closed);
}

// The scenes where log N fails (procedural.h): each test checks the property the scene exists for.

TEST(SceneSpecs, DustLetsAlmostEveryLineEscape) {
  const auto s = make_scene("dust:n=2000");
  EXPECT_EQ(s->triangle_count(), 2000u);
  EXPECT_TRUE(inside(s->bounds(), Bounds3f(Vec3f(0.0f), Vec3f(1.0f))));
  const auto brute = make_accelerator("brute", s);
  const auto lines = make_ray_set("lines:2000", s);
  const TraceResult r = trace_rays(*brute, lines, TraceOptions{1, false, false});
  EXPECT_LT(r.hit_count, lines.size() / 20) << "a dust cloud should let >95% of the lines through";
  EXPECT_GT(make_scene("dust:n=2000,size=0.2")->bounds().diagonal().x, 0.5f);
}

TEST(SceneSpecs, NeedlesBoxesAllOverlap) {
  const auto s = make_scene("needles:n=400");
  ASSERT_EQ(s->triangle_count(), 400u);
  EXPECT_EQ(describe(*s).degenerate_triangles, 0u);
  // The intersection of every needle's bounding box is a large part of the scene box.
  Bounds3f common = s->mesh.triangle_bounds(0);
  for (std::size_t t = 1; t < s->mesh.size(); ++t) common = intersect(common, s->mesh.triangle_bounds(t));
  ASSERT_FALSE(common.empty());
  const Vec3f scene = s->bounds().diagonal(), shared = common.diagonal();
  for (int a = 0; a < 3; ++a) EXPECT_GT(shared[a], 0.2f * scene[a]) << "axis " << a;
}

TEST(SceneSpecs, FanHasOneVertexOfValenceN) {
  const auto s = make_scene("fan:n=500");
  ASSERT_EQ(s->triangle_count(), 500u);
  EXPECT_EQ(s->mesh.vertices.size(), 501u);
  const Vec3f apex = s->mesh.vertices[0];
  for (std::size_t t = 0; t < s->mesh.size(); ++t) {
    EXPECT_EQ(s->mesh.triangles[t][0], 0u);
    EXPECT_TRUE(s->mesh.triangle_bounds(t).contains(apex));
  }
  EXPECT_EQ(describe(*s).degenerate_triangles, 0u);
  // Outward winding: the normal of every face points away from the axis and up.
  for (std::size_t t = 0; t < s->mesh.size(); t += 37) {
    const Vec3d a(s->mesh.vertex(t, 0)), b(s->mesh.vertex(t, 1)), c(s->mesh.vertex(t, 2));
    const Vec3d n = cross(b - a, c - a), mid = (b + c) * 0.5;
    EXPECT_GT(n.y, 0.0);
    EXPECT_GT(n.x * mid.x + n.z * mid.z, 0.0);
  }
}

TEST(SceneSpecs, RowRaysMissEveryTriangleInsideMostBoxes) {
  NearMissRowConfig c;
  c.triangles = 300;
  const auto s = make_scene("row:n=300");
  ASSERT_EQ(s->triangle_count(), 300u);
  const auto rays = near_miss_row_rays(c, 256, 7);
  const auto exact = make_accelerator("exact", s);
  EXPECT_EQ(trace_rays(*exact, rays, TraceOptions{1, false, false}).hit_count, 0u);
  for (const Ray& r : rays) {
    const Vec3f inv = safe_inverse(r.dir);
    std::size_t boxes = 0;
    for (std::size_t t = 0; t < s->mesh.size(); ++t) {
      float t0, t1;
      boxes += intersect_box(s->mesh.triangle_bounds(t), r, inv, r.tmin, r.tmax, t0, t1);
    }
    EXPECT_GT(boxes, s->mesh.size() / 2);
  }
  EXPECT_THROW(make_scene("row:gap=0.1,radius=0.2"), InputError);
}
