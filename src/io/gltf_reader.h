// glTF 2.0 files (.gltf with its buffers, or binary .glb), read through tinygltf (Debian's libtinygltf-dev) and
// turned into kozu's own descriptions: world-space triangle meshes, the materials as kozu "standard" material JSON
// (docs/scene-format.md, "gltf"), KHR_lights_punctual lights as kozu light JSON, and the first perspective camera.
//
// Specification: The Khronos Group, glTF 2.0 (2021), §3.5 (nodes and transforms), §3.6 (accessors), §3.7
// (meshes), §3.9 (materials), §3.8 (textures, samplers), §3.10 (cameras), and the extensions named below.
//
// What is imported
//   nodes       the default scene's hierarchy (scene 0 without a default; every root node without scenes), each
//               node's matrix or T·R·S, composed with `root`
//   meshes      positions, normals, tangents (xyz and the bitangent sign w), TEXCOORD_0 (v flipped: kozu's v is
//               up, glTF's is down, so v_kozu = 1 − v_glTF), indices of any component type, sparse accessors;
//               triangles, strips and fans (fans and strips become triangles)
//   materials   metallic-roughness with its textures, normal textures, alpha (BLEND and MASK → "opacity"),
//               emission (→ the shape's emission), KHR_texture_transform, KHR_materials_emissive_strength, ior,
//               transmission, volume (attenuation → a homogeneous absorbing medium inside the mesh), clearcoat,
//               sheen, specular
//   lights      KHR_lights_punctual point, spot and directional
//   camera      the first perspective camera a node of the scene carries
// KHR_mesh_quantization's integer attributes are read too. A required extension kozu lacks is an error.
// Everything else the file uses (other extensions, skins, morph targets, animations, texture sets other than
// TEXCOORD_0, points and lines, emissive textures, further cameras) is named in one warning.
//
// Images are not decoded here: external images are referenced by their path, and embedded ones (a bufferView or
// a data URI) are written once to `image_dir` and referenced there, so the texture cache reads them like any
// image file.
//
// Before tinygltf parses the JSON (a .gltf, or a .glb's JSON chunk; .glb version 2 only), its nesting depth is
// checked against kMaxJsonDepth (tinygltf's parser recurses) and negative offsets, lengths and counts are refused.
// Every accessor is checked against its buffer view and buffer before anything is read, every index against the
// vertex count, and the memory the meshes take is estimated and checked against the memory left before any is
// allocated. The node hierarchy is walked without recursion. A mesh several nodes use becomes one GltfObject
// placed by GltfInstances (unless it emits). Values below the glTF schema's minimum, and values kozu refuses in
// its own scenes (coordinates beyond ±1e15, an aspect ratio giving an image wider than 65536, non-affine
// matrices, emitters beyond 1e30 W), throw InputError naming the file and the glTF JSON path; values the schema
// allows but kozu's models cannot represent are clamped and named in one warning.
#pragma once

#include "core/color.h"
#include "core/json_reader.h"
#include "core/math.h"
#include "io/mesh_io.h"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace kozu {

struct GltfImportOptions {
  Mat4 root{1.0f};                   // applied after the file's own node transforms (the shape's transform)
  std::filesystem::path image_dir;   // where embedded images are written; empty: the temp dir's "kozu-gltf"
  double light_scale = 1.0 / 683.0;  // glTF candela/lux to kozu W/sr and W/m² (683 lm/W; "radiometric": 1)
  // A mesh several nodes use becomes one object placed by instances; false: a copy per node (an animated gltf
  // shape, whose keyed pose replaces `root` under every node).
  bool instance_meshes = true;
};

// The height in pixels of the image of a glTF camera when the file is rendered directly; its width is this height
// times the camera's aspectRatio, which must therefore give a width in [1, 65536].
inline constexpr int kGltfImageHeight = 720;

// One primitive of one mesh: in world space (GltfScene::primitives) or in its mesh's space (GltfObject).
struct GltfPrimitive {
  MeshData mesh;
  int material = -1;      // index into GltfScene::materials; -1: the glTF default material
  std::string json_path;  // "/meshes/2/primitives/0", for messages
};

// A mesh that several nodes place: its primitives stored once, in the mesh's own space, placed by instances.
struct GltfObject {
  std::string name;  // "mesh 3" or the mesh's name
  std::vector<GltfPrimitive> primitives;
};
struct GltfInstance {
  size_t object = 0;      // index into GltfScene::objects
  Mat4 transform{1.0f};   // mesh space to world (the node's world transform, then `root`)
  std::string json_path;  // "/nodes/7", for messages
};

struct GltfCamera {
  Vec3 position{0.0f}, forward{0.0f, 0.0f, -1.0f}, up{0.0f, 1.0f, 0.0f};
  float yfov_degrees = 40.0f;
  float aspect = 0.0f;  // 0: not given
};

struct GltfScene {
  // Meshes that one node uses, in world space, one entry per primitive.
  std::vector<GltfPrimitive> primitives;
  // Meshes that several nodes use (and that do not emit: an area light is one surface in world space): stored
  // once and placed by instances, so 400 nodes of one mesh cost one mesh.
  std::vector<GltfObject> objects;
  std::vector<GltfInstance> instances;
  // Per glTF material (and one more at the end for primitives without a material, when there are some): the
  // kozu material description, the emitted radiance, and the interior medium's description (null when none).
  std::vector<Json> materials;
  std::vector<std::string> material_names;
  std::vector<Rgb> emission;
  std::vector<bool> double_sided;  // glTF's doubleSided: an emissive surface then emits from both sides
  std::vector<Json> media;
  std::vector<Json> lights;  // kozu light descriptions, in world space
  std::optional<GltfCamera> camera;
  // At most two: "model.glb: not supported, ignored: …" and "model.glb: clamped to what kozu represents: …".
  std::vector<std::string> warnings;
  // Every file the import read or names (buffers, external images): the render's inputs, never an output.
  std::vector<std::filesystem::path> input_files;
  // The glTF JSON path of a path in the kozu descriptions above ("/materials/0/specular_color/2" →
  // "/materials/0/extensions/KHR_materials_specular/specularColorFactor/2", "/lights/1" →
  // "/extensions/KHR_lights_punctual/lights/3"), so that a message about them names the file's own keys. A path
  // the import did not write comes back unchanged.
  std::string gltf_path(const std::string& kozu_path) const;
  std::vector<std::pair<std::string, std::string>> paths;  // kozu path prefix → glTF path
};

// Reads file (.gltf or .glb). Throws InputError(file, json_path, message) for anything malformed, with the glTF's
// own JSON path.
GltfScene read_gltf(const std::filesystem::path& file, const GltfImportOptions& options = {});

}  // namespace kozu
