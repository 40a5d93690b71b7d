// Seeded, deterministic built-in scenes and procedural meshes (no external files needed).
#pragma once

#include <cstdint>
#include <optional>

#include "visbuf/core/result.h"
#include "visbuf/scene/scene.h"

namespace visbuf {

// A (2,3) torus knot, closed, ~28,800 triangles by default (similar to the peer's 28,944-triangle
// kitten), fitting in a unit-radius sphere.
MeshSource makeTorusKnot(uint32_t segments = 240, uint32_t sides = 60);
// Axis-aligned unit cube [-0.5,0.5]^3 with flat normals, each face split into n x n quads.
MeshSource makeBox(uint32_t subdivisions = 1);
// Flat square [-0.5,0.5]^2 in the XZ plane, facing +Y, split into n x n quads.
MeshSource makeGround(uint32_t subdivisions = 1);

struct FieldParams {
  uint32_t objects = 10000;
  uint64_t seed = 1;
  double extent = 300.0;  // positions uniform in [-extent, extent]^3
  std::optional<MeshSource> mesh;  // instanced mesh; the torus knot when empty
};
// The peer stress layout: N instances, positions uniform in the cube, scale in [2,4), random unit
// axis, angle in [0,90) degrees.
Result<Scene> makeFieldScene(const FieldParams& params);

struct AnimatedFieldParams {
  uint32_t instances = 1000;
  uint64_t seed = 1;
  double spacing = 3.0;  // instances stand on a jittered grid in the XZ plane, this far apart (normalised units)
};
// Many copies of an asset (a baked glTF such as Fox, CesiumMan or CesiumMilkTruck, or a pack), each scaled to a
// unit bounding radius, standing upright on a jittered grid with a random heading, its animated objects playing
// their clip at the copy's own random phase. The asset's meshes, materials, textures, skins, clips and node
// hierarchy are shared; every copy of a skinned object is a skinned instance of its own (its own vertex region
// and pose), every copy of a rigid object a rigid object of its own (placement: the copy's placement times the
// asset's; time offset: the asset's plus the copy's phase x the clip's duration; its object's transform
// rigidObjectStartTransform()). Static objects are copied as they are. The asset's point and spot lights go with
// every copy (moved with it; range x the copy's scale, intensity x its square), its directional lights and sun once.
// Fails when the asset has no objects.
Result<Scene> makeAnimatedField(const Scene& asset, const AnimatedFieldParams& params);

struct CityParams {
  uint32_t objects = 20000;  // approximate total (buildings + clutter + ground)
  uint64_t seed = 1;
};
// A grid of buildings with street clutter and a street-level camera: heavy occlusion.
Result<Scene> makeCityScene(const CityParams& params);

// Replaces a generated scene's materials with `count` procedural PBR materials (the many-material scenes of the
// material classification benchmark): three of four sample a base colour texture and half of those also a
// metallic-roughness texture (layers of two procedural texture classes: 128^2 sRGB checkers/stripes and 64^2
// linear noise, full mip chains, trilinear), the rest are untextured; factors vary per material. They keep the alpha
// mode, cutoff and sidedness of the scene's first material (foliage cards stay double-sided, and masked). Object i
// gets material hash(i, seed) % count, so neighbouring objects differ. Fails for count 0 or a scene that already
// has textures (a glTF asset keeps its own materials).
Status applyGeneratedMaterials(Scene& scene, uint32_t count, uint64_t seed);

struct FoliageParams {
  uint32_t cards = 20000;
  uint64_t seed = 1;
  double extent = 30.0;  // card centres uniform in [-extent, extent] x [0, extent / 3] x [-extent, extent]
  bool masked = true;    // MASK (cutoff 0.5) or the same cards OPAQUE: the masked pipeline's cost, measured
};
// Foliage-like: double-sided unit cards (scaled 1..3) at random orientations whose COLOR_0 alpha runs from 0 to 1
// across each card, so a MASK material with cutoff 0.5 keeps exactly half of every card.
Result<Scene> makeFoliageScene(const FoliageParams& params);

inline constexpr uint32_t kTerrainMinSize = 2;
// 8193^2 vertices, 2 x 8192^2 = 134M triangles: the 32-bit index range holds its 402M indices. Building costs about
// 400 bytes of memory per vertex at its peak (buildMesh: 6.5 GiB at 4097^2 without a LOD chain), so the largest
// sizes need a large machine.
inline constexpr uint32_t kTerrainMaxSize = 8193;

struct TerrainParams {
  uint32_t size = 4097;  // vertices per side, kTerrainMinSize..kTerrainMaxSize: 2 (size - 1)^2 triangles
  uint64_t seed = 1;
};
// A heightfield of size x size vertices over a fixed 2048 x 2048-unit square in XZ (centred on the origin, facing
// +Y, heights about +-90 units): fractal value noise from `seed` (the same landscape at every size, with detail
// down to about four grid cells), normals from the sampled heights, TEXCOORD_0 tiling every 32 units. One open
// mesh (its outer edge is its border). InvalidArgument for a size outside kTerrainMinSize..kTerrainMaxSize.
Result<MeshSource> makeTerrainMesh(const TerrainParams& params);
// The terrain as one object (buildMesh of makeTerrainMesh: a per-object chain of coarse levels up to 2^21 triangles,
// level 0 only above), one material, and a default camera low and grazing: 3 units above the ground near the +Z
// edge, looking across to the far edge, so that it is near and far at once.
Result<Scene> makeTerrainScene(const TerrainParams& params);
// That default camera (cheap: the mesh is not built). params.size must be valid.
Camera terrainCamera(const TerrainParams& params);

// Deterministic generator (splitmix64), identical on every platform.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed * 0x9E3779B97F4A7C15ull + 0x2545F4914F6CDD1Dull) {}
  uint64_t next();
  double uniform() { return double(next() >> 11) * 0x1.0p-53; }  // [0,1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

 private:
  uint64_t state_;
};

}  // namespace visbuf
