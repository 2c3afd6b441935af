#pragma once
/// Scenes from spec strings (`name:key=value,...`, see geometry/spec_string.h):
///
///   cgal:NAME            a CGAL demo mesh (cgal_meshes.h), e.g. `cgal:bunny00`
///   file:PATH            a scene file (file_format.h): OFF/OBJ/PLY/STL as one mesh (mesh_io.h),
///                        glTF 2.0/FBX/COLLADA/3DS with their node tree (scene_import.h);
///                        `file:(PATH)` when PATH holds ',' or ':'
///   PATH                 a bare path with one of those extensions, or naming an existing file
///   sphere, sphereflake, stadium, grass, walls, soup, dust, needles, fan, row, subdivided,
///   decimated, instances
///                        the procedural scenes of procedural.h; nested scenes are specs too:
///                        `stadium:object=(sphereflake:depth=2),ratio=1000`
#include <memory>
#include <string>
#include <vector>

#include "geometry/spec_string.h"
#include "scene/scene.h"

namespace raylab {

/// Builds the scene a spec names and sets Scene::spec to it. Throws InputError (naming the
/// spec) on unknown scene kinds (listing the valid ones), unknown or malformed parameters,
/// unreadable meshes and empty scenes.
std::shared_ptr<const Scene> make_scene(const std::string& spec);

/// One scene kind, for `--help` listings.
struct SceneKindDoc {
  std::string name, summary;
  std::vector<ParamDoc> params;
};

/// Every scene kind make_scene accepts, in listing order.
const std::vector<SceneKindDoc>& scene_kinds();

}  // namespace raylab
