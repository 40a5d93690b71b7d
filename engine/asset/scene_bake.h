// Turns an imported glTF scene (gltf_import.h) into a render-ready Scene: every mesh through buildMesh()
// (meshoptimizer optimisation + LOD chain), instances as objects (skinned instances also as skinnedObjects, rigid
// ones also as rigidObjects), nodes / skins / animations as they are, and a default camera that frames the
// time-0 pose.
// Shared by `visbuf bake` (which then writes a pack) and `visbuf render --scene FILE.gltf` (in memory).
#pragma once

#include <cstddef>
#include <functional>
#include <string>

#include "visbuf/asset/gltf_import.h"
#include "visbuf/core/result.h"
#include "visbuf/scene/scene.h"

namespace visbuf {

// Called after each mesh is built: (meshes done, meshes total, name of the mesh just built). Calls never overlap
// and `done` counts up by one per call, but meshes finish in any order, on any of the bake's threads.
using BakeProgress = std::function<void(size_t done, size_t total, const std::string& mesh)>;

// Builds every imported mesh with `options` in parallel (oneTBB; the caller limits the threads with
// tbb::global_control), keeping the order (scene.meshes[i] comes from imported.meshes[i]), so the result does not
// depend on the thread count. Each mesh's triangles are rotated into the order the pack's index codec reproduces
// (pack::rotateTrianglesToCodecOrder). Then copies materials, turns instances into objects and calls
// frameScene(). A rigid instance (ImportedInstance::rigid) becomes a RigidObject playing firstClipMoving() of its
// node from time 0 in place, its object's transform rigidObjectStartTransform() (scene.h). Errors name the mesh
// (the first failing one in mesh order).
Result<Scene> buildImportedScene(const ImportedScene& imported, const MeshBuildOptions& options = {},
                                 const BakeProgress& progress = {});

// The first clip (Scene::animations index) with a translation / rotation / scale channel on `node` or on an
// ancestor of it; -1 when none moves it.
int32_t firstClipMoving(const Scene& scene, int32_t node);

// World-space bounding sphere of all objects (xyz centre, w radius; double precision, conservative).
// Returns (0,0,0,0) for a scene without objects.
glm::dvec4 sceneBounds(const Scene& scene);

// Sets scene.anchor to the centre of animatedSceneBounds() (scene.h: every object over every clip, so that animated
// parts stay in frame) and the default camera to look at that centre from the (0.35, 0.3, 1) direction, far enough
// for the bounding sphere to fit the camera's vertical field of view (plus 5 %), with a near plane of 1e-3 x the
// radius (at least 1e-4).
void frameScene(Scene& scene);

}  // namespace visbuf
