// The glTF importer (io/gltf_reader.h) against small files written here, with every expected value computed by
// hand from the glTF 2.0 specification: node transforms, units, texture transforms with kozu's v flip, materials,
// lights and their units, the one warning, and malformed files.
#include "io/gltf_test_files.h"
#include "support/memory_limit_env.h"
#include "support/render_test.h"

#include "core/error.h"
#include "core/memory.h"
#include "geometry/instance.h"
#include "io/gltf_reader.h"
#include "scene/scene_loader.h"
#include "textures/image_texture.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>

namespace kozu::test {
namespace {

using nlohmann::json;

GltfScene import(const TempDir& dir, GltfBuilder& b, const std::string& name = "t.gltf",
                 const GltfImportOptions& opt = {}) {
  const auto file = dir.write(name, name.ends_with(".glb") ? b.glb() : b.gltf());
  GltfImportOptions o = opt;
  if (o.image_dir.empty()) o.image_dir = dir.path() / "images";
  return read_gltf(file, o);
}

void expect_near(const Vec3& a, const Vec3& b, float tol = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

// The message of the InputError read_gltf throws ("" when it does not throw).
std::string import_error(const std::filesystem::path& file) {
  try {
    read_gltf(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// A child node (translated by (1, 0, 0) through a column-major matrix) under a parent translated by (1, 2, 3),
// rotated 90° about +y and scaled by 2: the child's origin lands at T R S (1, 0, 0) = (1, 2, 3) + R (2, 0, 0) and
// R_y(90°) takes (2, 0, 0) to (0, 0, −2), so at (1, 2, 1).
TEST(Gltf, ChildNodeUnderTranslatedRotatedScaledParent) {
  TempDir dir;
  GltfBuilder b;
  const int child = b.triangle_node();
  b.doc["nodes"][child]["matrix"] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 1};
  const float h = std::sqrt(0.5f);
  b.doc["nodes"].push_back(
      {{"children", {child}}, {"translation", {1, 2, 3}}, {"rotation", {0, h, 0, h}}, {"scale", {2, 2, 2}}});
  b.doc["scenes"] = {{{"nodes", {1}}}};
  const GltfScene s = import(dir, b);
  ASSERT_EQ(s.primitives.size(), 1u);
  const MeshData& m = s.primitives[0].mesh;
  // Vertices (0,0,0), (1,0,0), (0,1,0) in the child: parent(child(p)) = (1,2,3) + R_y(90°)·2·(p + (1,0,0)).
  expect_near(m.positions[0], Vec3(1, 2, 1));
  expect_near(m.positions[1], Vec3(1, 2, -1));
  expect_near(m.positions[2], Vec3(1, 4, 1));
  // The normal +z turns to +x under R_y(90°).
  expect_near(m.normals[0], Vec3(1, 0, 0));
  EXPECT_TRUE(s.warnings.empty());
}

// The same transform given as a matrix or as T, R, S gives the same vertices; the shape's transform (root)
// applies after the file's.
TEST(Gltf, MatrixAndTrsAgreeAndRootAppliesLast) {
  TempDir dir;
  const float h = std::sqrt(0.5f);
  // T(1,2,3) R_x(90°) S(1,2,3) as a column-major matrix: R_x(90°) maps y → z, z → −y.
  const std::vector<float> matrix = {1, 0, 0, 0, 0, 0, 2, 0, 0, -3, 0, 0, 1, 2, 3, 1};
  GltfBuilder a, c;
  a.triangle_node();
  a.doc["nodes"][0]["matrix"] = matrix;
  c.triangle_node();
  c.doc["nodes"][0]["translation"] = {1, 2, 3};
  c.doc["nodes"][0]["rotation"] = {h, 0, 0, h};
  c.doc["nodes"][0]["scale"] = {1, 2, 3};
  GltfImportOptions opt;
  opt.root = glm::translate(Mat4(1.0f), Vec3(10, 0, 0));
  const GltfScene sa = import(dir, a, "a.gltf", opt), sc = import(dir, c, "c.gltf", opt);
  ASSERT_EQ(sa.primitives.size(), 1u);
  ASSERT_EQ(sc.primitives.size(), 1u);
  for (int i = 0; i < 3; ++i) expect_near(sa.primitives[0].mesh.positions[i], sc.primitives[0].mesh.positions[i]);
  // (0, 1, 0) → S: (0, 2, 0) → R_x: (0, 0, 2) → T: (1, 2, 5) → root: (11, 2, 5). glTF metres are scene units.
  expect_near(sa.primitives[0].mesh.positions[2], Vec3(11, 2, 5));
  expect_near(sa.primitives[0].mesh.positions[0], Vec3(11, 2, 3));
}

// A mirroring transform keeps the front side: the winding reverses and tangents' handedness flips.
TEST(Gltf, MirroringReversesWindingAndTangentSign) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node();
  b.doc["meshes"][0]["primitives"][0]["attributes"]["TANGENT"] =
      b.floats({1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, -1}, "VEC4");
  b.doc["nodes"][0]["scale"] = {-1, 1, 1};
  const GltfScene s = import(dir, b);
  const MeshData& m = s.primitives[0].mesh;
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 2, 1}));
  ASSERT_EQ(m.tangents.size(), 3u);
  EXPECT_EQ(m.tangents[0], Vec4(-1, 0, 0, -1));
  EXPECT_EQ(m.tangents[2], Vec4(-1, 0, 0, 1));
  expect_near(m.normals[0], Vec3(0, 0, 1));  // the inverse transpose of diag(−1, 1, 1) keeps +z
}

// TEXCOORD_0 (0.25, 0.1) in glTF (v down the image) is (0.25, 0.9) in kozu (v up). Strips become triangles with
// the strip's alternating winding; 8-bit indices read.
TEST(Gltf, UvFlipStripsAndByteIndices) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node();
  const GltfScene s = import(dir, b);
  EXPECT_EQ(s.primitives[0].mesh.uvs[0], Vec2(0.25f, 0.9f));
  EXPECT_EQ(s.primitives[0].mesh.uvs[1], Vec2(1.0f, 1.0f));

  GltfBuilder st;
  st.floats({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0}, "VEC3");  // accessor 0
  const uint8_t idx[4] = {0, 1, 2, 3};
  const int view = st.bytes_view(std::string(reinterpret_cast<const char*>(idx), 4));
  st.doc["accessors"].push_back({{"bufferView", view}, {"componentType", 5121}, {"count", 4}, {"type", "SCALAR"}});
  st.doc["meshes"] = json::parse(R"([{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 5}]}])");
  st.doc["nodes"] = json::parse(R"([{"mesh": 0}])");
  const GltfScene ss = import(dir, st, "strip.gltf");
  // Triangle i of a strip is (i, i + 1 + i % 2, i + 2 − i % 2) (§3.7.2.1).
  EXPECT_EQ(ss.primitives[0].mesh.indices, (std::vector<uint32_t>{0, 1, 2, 1, 3, 2}));
}

// A sparse accessor (§3.6.2.3): the base positions with element 2 replaced; without a bufferView the base is zeros.
TEST(Gltf, SparseAccessors) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node();
  const uint16_t which[1] = {2};
  const float value[3] = {0, 5, 0};
  const int iv = b.bytes_view(std::string(reinterpret_cast<const char*>(which), 2));
  const int vv = b.bytes_view(std::string(reinterpret_cast<const char*>(value), 12));
  b.doc["accessors"][0]["sparse"] = {
      {"count", 1}, {"indices", {{"bufferView", iv}, {"componentType", 5123}}}, {"values", {{"bufferView", vv}}}};
  const GltfScene s = import(dir, b);
  EXPECT_EQ(s.primitives[0].mesh.positions[1], Vec3(1, 0, 0));
  EXPECT_EQ(s.primitives[0].mesh.positions[2], Vec3(0, 5, 0));
  GltfBuilder z = b;
  z.doc["accessors"][0].erase("bufferView");
  const GltfScene sz = import(dir, z, "z.gltf");
  EXPECT_EQ(sz.primitives[0].mesh.positions[1], Vec3(0, 0, 0));
  EXPECT_EQ(sz.primitives[0].mesh.positions[2], Vec3(0, 5, 0));
  // A substitution index past the accessor's count.
  const uint16_t far[1] = {3};
  GltfBuilder bad = b;
  bad.doc["accessors"][0]["sparse"]["indices"]["bufferView"] =
      bad.bytes_view(std::string(reinterpret_cast<const char*>(far), 2));
  EXPECT_EQ(import_error(dir.write("bad.gltf", bad.gltf())),
            (dir.path() / "bad.gltf").string() + ": /accessors/0/sparse/indices: index 3 is out of range (count 3)");
}

// KHR_mesh_quantization: positions as signed shorts (as stored), normals as normalized signed bytes, UVs as
// normalized unsigned shorts.
TEST(Gltf, QuantizedAttributes) {
  TempDir dir;
  GltfBuilder b;
  const int16_t pos[12] = {0, 0, 0, 0, 0, 0, -3, 0, 0, 200, 0, 0};  // 3 VEC3, each padded to 8 bytes
  const int8_t nrm[12] = {0, 0, 127, 0, 0, -128, 0, 0, 0, 127, 0, 0};
  const uint16_t uv[6] = {0, 65535, 65535, 0, 0, 0};
  const int pv = b.bytes_view(std::string(reinterpret_cast<const char*>(pos), sizeof pos));
  b.doc["bufferViews"][pv]["byteStride"] = 8;
  const int nv = b.bytes_view(std::string(reinterpret_cast<const char*>(nrm), sizeof nrm));
  b.doc["bufferViews"][nv]["byteStride"] = 4;
  const int uvv = b.bytes_view(std::string(reinterpret_cast<const char*>(uv), sizeof uv));
  b.doc["accessors"] = json::parse(fmt::format(R"([
      {{"bufferView": {}, "componentType": 5122, "count": 3, "type": "VEC3"}},
      {{"bufferView": {}, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC3"}},
      {{"bufferView": {}, "componentType": 5123, "normalized": true, "count": 3, "type": "VEC2"}}])",
                                               pv, nv, uvv));
  b.doc["meshes"] = json::parse(R"([{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}}]}])");
  b.doc["nodes"] = json::parse(R"([{"mesh": 0}])");
  b.doc["extensionsUsed"] = {"KHR_mesh_quantization"};
  b.doc["extensionsRequired"] = {"KHR_mesh_quantization"};
  const GltfScene s = import(dir, b);
  const MeshData& m = s.primitives[0].mesh;
  EXPECT_EQ(m.positions[0], Vec3(0, 0, 0));
  EXPECT_EQ(m.positions[1], Vec3(0, 0, -3));
  EXPECT_EQ(m.positions[2], Vec3(0, 200, 0));
  EXPECT_EQ(m.normals[0], Vec3(0, 0, 1));
  EXPECT_EQ(m.normals[1], Vec3(0, -1, 0));  // −128 clamps to −1
  EXPECT_EQ(m.uvs[0], Vec2(0, 0));          // glTF (0, 1) with v flipped
  EXPECT_EQ(m.uvs[1], Vec2(1, 1));
  EXPECT_TRUE(s.warnings.empty());
  // An extension the file requires and kozu lacks is an error, not a warning.
  b.doc["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  EXPECT_EQ(import_error(dir.write("draco.gltf", b.gltf())),
            (dir.path() / "draco.gltf").string() +
                ": /extensionsRequired: requires extensions kozu does not support: KHR_draco_mesh_compression");
}

// KHR_texture_transform: kozu's image texture, with the keys the importer wrote, looks up the same image point
// as glTF's uv' = T R S uv for the same surface point (kozu's v = 1 − glTF's v).
TEST(Gltf, TextureTransformMatchesTheGltfDefinition) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node({0, 0, 0, 1, 0, 0, 0, 1, 0}, 0);
  b.doc["images"] = {{{"uri", "wood.png"}}};
  b.doc["textures"] = {{{"source", 0}}};
  const double ox = 0.1, oy = 0.2, rot = 0.3, sx = 2.0, sy = 3.0;
  b.doc["materials"] = json::parse(R"([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
      "extensions": {"KHR_texture_transform": {"offset": [0.1, 0.2], "rotation": 0.3, "scale": [2, 3]}}}}}])");
  b.doc["extensionsUsed"] = {"KHR_texture_transform"};
  const GltfScene s = import(dir, b);
  const json& t = s.materials[0]["base_color"];
  ASSERT_EQ(t["type"], "image");
  EXPECT_EQ(std::filesystem::path(t["file"].get<std::string>()), dir.path() / "wood.png");
  EXPECT_EQ(t["colorspace"], "srgb");
  ImageTexture::Options o;
  o.uv_scale = Vec2(t["uv_scale"][0].get<float>(), t["uv_scale"][1].get<float>());
  o.uv_offset = Vec2(t["uv_offset"][0].get<float>(), t["uv_offset"][1].get<float>());
  o.uv_rotation = t["uv_rotation"].get<float>();
  for (const Vec2 g : {Vec2(0, 0), Vec2(0.25f, 0.1f), Vec2(0.7f, 0.9f), Vec2(-1.5f, 2.0f)}) {
    // The glTF lookup (§ KHR_texture_transform): translation · rotation · scale, rotation [c s; −s c].
    const double c = std::cos(rot), n = std::sin(rot);
    const double su = c * sx * g.x + n * sy * g.y + ox, tv = -n * sx * g.x + c * sy * g.y + oy;
    const Vec2 st = ImageTexture::lookup_coordinates(o, Vec2(g.x, 1.0f - g.y));
    EXPECT_NEAR(st.x, su, 1e-5) << g.x << ", " << g.y;
    EXPECT_NEAR(st.y, tv, 1e-5) << g.x << ", " << g.y;
  }
  // Without a transform the v flip needs no keys: kozu's t = 1 − v_kozu is glTF's v.
  GltfBuilder plain;
  plain.triangle_node({0, 0, 0, 1, 0, 0, 0, 1, 0}, 0);
  plain.doc["images"] = b.doc["images"];
  plain.doc["textures"] = b.doc["textures"];
  plain.doc["materials"] = json::parse(R"([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}])");
  const json p = import(dir, plain, "plain.gltf").materials[0]["base_color"];
  EXPECT_FALSE(p.contains("uv_offset"));
  EXPECT_FALSE(p.contains("uv_scale"));
  EXPECT_FALSE(p.contains("uv_rotation"));
}

// An 8-bit RGBA PNG (2 × 2) for embedded images.
std::string rgba_png(const TempDir& dir) {
  const auto file = dir.path() / "src.png";
  auto out = OIIO::ImageOutput::create(file.string());
  const OIIO::ImageSpec spec(2, 2, 4, OIIO::TypeDesc::UINT8);
  const unsigned char px[16] = {255, 0, 0, 128, 0, 255, 0, 255, 0, 0, 255, 64, 255, 255, 255, 0};
  EXPECT_TRUE(out->open(file.string(), spec));
  EXPECT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, px));
  out->close();
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Materials per §3.9 and the extensions: factors multiply textures, metallic is B and roughness G of one linear
// texture, the normal scale, alpha from the base colour's alpha channel, emission × strength, and the rest.
TEST(Gltf, MaterialsFollowTheGltfDefinition) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node({0, 0, 0, 1, 0, 0, 0, 1, 0}, 0);
  const std::string png = rgba_png(dir);
  b.doc["images"] = {{{"bufferView", b.bytes_view(png)}, {"mimeType", "image/png"}},
                     {{"uri", "data:image/png;base64," + base64(png)}}};
  b.doc["textures"] = {{{"source", 0}}, {{"source", 1}}};
  b.doc["extensionsUsed"] = {
      "KHR_materials_emissive_strength", "KHR_materials_ior",   "KHR_materials_transmission", "KHR_materials_volume",
      "KHR_materials_clearcoat",         "KHR_materials_sheen", "KHR_materials_specular"};
  b.doc["materials"] = {
      {{"pbrMetallicRoughness",
        {{"baseColorFactor", {0.5, 0.6, 0.7, 0.8}},
         {"baseColorTexture", {{"index", 0}}},
         {"metallicFactor", 0.8},
         {"roughnessFactor", 0.4},
         {"metallicRoughnessTexture", {{"index", 1}}}}},
       {"normalTexture", {{"index", 1}, {"scale", 0.7}}},
       {"alphaMode", "BLEND"},
       {"emissiveFactor", {1, 0.5, 0.25}},
       {"extensions",
        {{"KHR_materials_emissive_strength", {{"emissiveStrength", 4}}},
         {"KHR_materials_ior", {{"ior", 1.33}}},
         {"KHR_materials_transmission", {{"transmissionFactor", 0.9}}},
         {"KHR_materials_volume", {{"attenuationDistance", 2.0}, {"attenuationColor", {0.5, 1.0, 0.25}}}},
         {"KHR_materials_clearcoat", {{"clearcoatFactor", 1.0}, {"clearcoatRoughnessFactor", 0.1}}},
         {"KHR_materials_sheen", {{"sheenColorFactor", {0.2, 0.3, 0.4}}, {"sheenRoughnessFactor", 0.5}}},
         {"KHR_materials_specular", {{"specularFactor", 0.5}, {"specularColorFactor", {1, 0.9, 0.8}}}}}}}};
  // A relative image folder (kozu render's is beside the output): the descriptions still name absolute paths, since
  // they resolve against the glTF file's folder.
  GltfImportOptions opt;
  opt.image_dir = std::filesystem::relative(dir.path() / "images", std::filesystem::current_path());
  ASSERT_TRUE(opt.image_dir.is_relative());
  const GltfScene s = import(dir, b, "t.gltf", opt);
  ASSERT_EQ(s.materials.size(), 1u);
  const json& m = s.materials[0];
  EXPECT_EQ(m["type"], "standard");
  // Base colour: the sRGB texture times the factor's rgb.
  EXPECT_EQ(m["base_color"]["colorspace"], "srgb");
  EXPECT_EQ(m["base_color"]["scale"], json({0.5, 0.6, 0.7}));
  EXPECT_FALSE(m["base_color"].contains("channel"));
  // The embedded image was written out once and is read from there.
  const std::filesystem::path written = m["base_color"]["file"].get<std::string>();
  EXPECT_EQ(written.parent_path(), dir.path() / "images");
  EXPECT_EQ(std::filesystem::file_size(written), png.size());
  // Metallic: channel b, roughness: channel g, linear, times their factors; the data-URI image also written out.
  EXPECT_EQ(m["metallic"]["channel"], "b");
  EXPECT_EQ(m["metallic"]["colorspace"], "linear");
  EXPECT_DOUBLE_EQ(m["metallic"]["scale"].get<double>(), 0.8);
  EXPECT_EQ(m["roughness"]["channel"], "g");
  EXPECT_DOUBLE_EQ(m["roughness"]["scale"].get<double>(), 0.4);
  EXPECT_EQ(m["roughness"]["file"], m["metallic"]["file"]);
  EXPECT_NE(m["roughness"]["file"], m["base_color"]["file"]);
  EXPECT_EQ(m["normal_map"]["colorspace"], "linear");
  EXPECT_DOUBLE_EQ(m["normal_map_strength"].get<double>(), 0.7);
  // BLEND: opacity is the base colour texture's alpha (linear) times the factor's alpha.
  EXPECT_EQ(m["opacity"]["channel"], "a");
  EXPECT_EQ(m["opacity"]["colorspace"], "linear");
  EXPECT_EQ(m["opacity"]["file"], m["base_color"]["file"]);
  EXPECT_NEAR(m["opacity"]["scale"].get<double>(), 0.8, 1e-12);
  EXPECT_FALSE(m["opacity"].contains("threshold"));
  // MASK: the same alpha, cut at alphaCutoff after the factor.
  GltfBuilder mask = b;
  mask.doc["materials"][0]["alphaMode"] = "MASK";
  mask.doc["materials"][0]["alphaCutoff"] = 0.3;
  const json mo = import(dir, mask, "mask.gltf", opt).materials[0]["opacity"];
  EXPECT_EQ(mo["channel"], "a");
  EXPECT_NEAR(mo["scale"].get<double>(), 0.8, 1e-12);
  EXPECT_NEAR(mo["threshold"].get<double>(), 0.3, 1e-12);
  // Emission is the factor times the strength.
  EXPECT_EQ(s.emission[0], Rgb(4, 2, 1));
  EXPECT_DOUBLE_EQ(m["ior"].get<double>(), 1.33);
  EXPECT_DOUBLE_EQ(m["transmission"].get<double>(), 0.9);
  EXPECT_DOUBLE_EQ(m["clearcoat"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(m["clearcoat_roughness"].get<double>(), 0.1);
  EXPECT_EQ(m["sheen_color"], json({0.2, 0.3, 0.4}));
  EXPECT_DOUBLE_EQ(m["sheen_roughness"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(m["specular"].get<double>(), 0.5);
  EXPECT_EQ(m["specular_color"], json({1, 0.9, 0.8}));
  // Volume: σa = −ln(c) / d per channel, a purely absorbing medium.
  const json& med = s.media[0];
  ASSERT_TRUE(med.is_object());
  EXPECT_EQ(med["type"], "homogeneous");
  EXPECT_NEAR(med["density"][0].get<double>(), std::log(2.0) / 2.0, 1e-12);
  EXPECT_NEAR(med["density"][1].get<double>(), 0.0, 1e-12);
  EXPECT_NEAR(med["density"][2].get<double>(), std::log(4.0) / 2.0, 1e-12);
  EXPECT_EQ(med["albedo"], 0.0);
  EXPECT_TRUE(s.warnings.empty()) << s.warnings[0];
}

// The glTF defaults: no material gives the default material (white, metallic 1, roughness 1); factors alone;
// OPAQUE ignores alpha.
TEST(Gltf, DefaultMaterialAndFactors) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node();
  b.triangle_node({0, 0, 0, 1, 0, 0, 0, 1, 0}, 0);
  b.doc["materials"] = {{{"pbrMetallicRoughness", {{"baseColorFactor", {0.1, 0.2, 0.3, 0.5}}, {"metallicFactor", 0}}}}};
  b.doc["scenes"] = {{{"nodes", {0, 1}}}};
  const GltfScene s = import(dir, b);
  ASSERT_EQ(s.materials.size(), 2u);  // the file's and the default
  EXPECT_EQ(s.primitives[0].material, 1);
  EXPECT_EQ(s.primitives[1].material, 0);
  EXPECT_EQ(s.materials[1]["base_color"], json({1.0, 1.0, 1.0}));
  EXPECT_EQ(s.materials[1]["metallic"], 1.0);
  EXPECT_EQ(s.materials[1]["roughness"], 1.0);
  EXPECT_EQ(s.materials[0]["base_color"], json({0.1, 0.2, 0.3}));
  EXPECT_EQ(s.materials[0]["metallic"], 0.0);
  EXPECT_FALSE(s.materials[0].contains("opacity"));  // OPAQUE ignores alpha 0.5
  // MASK without a texture: the factor's alpha against the cutoff decides, opacity 0 or (left out) 1.
  GltfBuilder mask;
  mask.triangle_node({0, 0, 0, 1, 0, 0, 0, 1, 0}, 0);
  mask.doc["materials"] = {
      {{"alphaMode", "MASK"}, {"alphaCutoff", 0.6}, {"pbrMetallicRoughness", {{"baseColorFactor", {1, 1, 1, 0.5}}}}},
      {{"alphaMode", "MASK"}, {"pbrMetallicRoughness", {{"baseColorFactor", {1, 1, 1, 0.5}}}}}};
  const GltfScene sm = import(dir, mask, "mask.gltf");
  EXPECT_EQ(sm.materials[0]["opacity"], 0.0);
  EXPECT_FALSE(sm.materials[1].contains("opacity"));  // 0.5 reaches the default cutoff 0.5
  EXPECT_TRUE(sm.warnings.empty());
  EXPECT_EQ(s.emission[0], Rgb(0.0f));
  EXPECT_FALSE(s.double_sided[0]);
}

// KHR_lights_punctual: candela and lux over 683 lm/W (or as given, radiometric), placed by their nodes (lights
// shine down −z), spot cone angles in degrees.
TEST(Gltf, LightsAndTheirUnits) {
  TempDir dir;
  GltfBuilder b;
  const float h = std::sqrt(0.5f);
  b.doc["extensionsUsed"] = {"KHR_lights_punctual"};
  b.doc["extensions"]["KHR_lights_punctual"]["lights"] = {
      {{"type", "point"}, {"color", {1, 0.5, 0.25}}, {"intensity", 683}},
      {{"type", "spot"}, {"intensity", 1366}, {"spot", {{"innerConeAngle", 0.25}, {"outerConeAngle", 0.5}}}},
      {{"type", "directional"}, {"intensity", 6830}}};
  b.doc["nodes"] = {{{"translation", {1, 2, 3}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}},
                    // Rotated −90° about x: −z turns to −y (pointing down).
                    {{"translation", {0, 5, 0}},
                     {"rotation", {-h, 0, 0, h}},
                     {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}},
                    {{"rotation", {0, h, 0, h}}, {"extensions", {{"KHR_lights_punctual", {{"light", 2}}}}}}};
  const GltfScene s = import(dir, b);
  ASSERT_EQ(s.lights.size(), 3u);
  const json& p = s.lights[0];
  EXPECT_EQ(p["type"], "point");
  EXPECT_EQ(p["position"], json({1.0, 2.0, 3.0}));
  EXPECT_NEAR(p["intensity"][0].get<double>(), 1.0, 1e-12);
  EXPECT_NEAR(p["intensity"][1].get<double>(), 0.5, 1e-12);
  EXPECT_NEAR(p["intensity"][2].get<double>(), 0.25, 1e-12);
  const json& sp = s.lights[1];
  EXPECT_EQ(sp["type"], "spot");
  EXPECT_NEAR(sp["direction"][1].get<double>(), -1.0, 1e-6);
  EXPECT_NEAR(sp["intensity"][0].get<double>(), 2.0, 1e-12);
  EXPECT_NEAR(sp["cone_angle"].get<double>(), 0.5 * 180 / M_PI, 1e-4);
  EXPECT_NEAR(sp["falloff_angle"].get<double>(), 0.25 * 180 / M_PI, 1e-4);
  const json& d = s.lights[2];
  EXPECT_EQ(d["type"], "directional");
  // R_y(90°) takes −z to −x: the light travels towards −x.
  EXPECT_NEAR(d["direction"][0].get<double>(), -1.0, 1e-6);
  EXPECT_NEAR(d["irradiance"][0].get<double>(), 10.0, 1e-9);
  EXPECT_EQ(d["angular_diameter"], 0.53);
  GltfImportOptions radiometric;
  radiometric.light_scale = 1.0;
  EXPECT_NEAR(import(dir, b, "r.gltf", radiometric).lights[0]["intensity"][0].get<double>(), 683.0, 1e-9);
}

// What the importer leaves out is named in one warning, extensions first, then features with their counts.
TEST(Gltf, UnsupportedFeaturesAreNamedInOneWarning) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node({0, 0, 0, 1, 0, 0, 0, 1, 0}, 0);
  b.doc["extensionsUsed"] = {"KHR_materials_iridescence", "KHR_texture_transform", "EXT_meshopt_compression"};
  b.doc["skins"] = {{{"joints", {0}}}, {{"joints", {0}}}};
  b.doc["images"] = {{{"uri", "a.png"}}};
  b.doc["textures"] = {{{"source", 0}}};
  b.doc["materials"] = {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}, {"texCoord", 1}}}}},
                         {"occlusionTexture", {{"index", 0}}}}};
  b.doc["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", 0.7}, {"znear", 0.1}}}}};
  b.doc["nodes"].push_back({{"camera", 0}});
  b.doc["nodes"].push_back({{"camera", 0}});
  b.doc["scenes"] = {{{"nodes", {0, 1, 2}}}};
  const GltfScene s = import(dir, b, "w.gltf");
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_EQ(s.warnings[0],
            "w.gltf: not supported, ignored: EXT_meshopt_compression, KHR_materials_iridescence, cameras beyond the "
            "first (1), occlusion textures (1), skins (2), textures using TEXCOORD_1 or higher (1)");
  // The texture on TEXCOORD_1 is dropped: the factor (glTF's default white) stays.
  EXPECT_EQ(s.materials[0]["base_color"], json({1.0, 1.0, 1.0}));
  ASSERT_TRUE(s.camera.has_value());
  EXPECT_NEAR(s.camera->yfov_degrees, 0.7 * 180 / M_PI, 1e-4);
}

TEST(Gltf, MalformedFilesGiveOneErrorNamingTheFile) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node();
  const std::string glb = b.glb();
  // A .glb cut short.
  const auto cut = dir.write("cut.glb", glb.substr(0, glb.size() - 20));
  EXPECT_NE(import_error(cut).find("cut.glb"), std::string::npos) << import_error(cut);
  EXPECT_NE(import_error(dir.write("empty.glb", "")).find("empty.glb"), std::string::npos);
  EXPECT_NE(import_error(dir.write("junk.gltf", "{\"asset\": ")).find("junk.gltf"), std::string::npos);
  // The same file whole reads.
  EXPECT_EQ(import_error(dir.write("whole.glb", glb)), "");

  // An accessor whose elements run past its buffer view.
  GltfBuilder over = b;
  over.doc["accessors"][0]["count"] = 4;
  EXPECT_EQ(import_error(dir.write("over.gltf", over.gltf())),
            (dir.path() / "over.gltf").string() +
                ": /accessors/0: byteOffset 0 with 4 elements of stride 12 exceeds bufferView 0 (36 bytes)");
  // A buffer view past its buffer.
  GltfBuilder view = b;
  view.doc["bufferViews"][0]["byteLength"] = 100000;
  EXPECT_NE(import_error(dir.write("view.gltf", view.gltf())).find("view.gltf"), std::string::npos);
  // An index past the vertex count.
  GltfBuilder idx;
  idx.triangle_node();
  idx.doc["meshes"][0]["primitives"][0]["indices"] = idx.indices({0, 1, 7});
  EXPECT_EQ(import_error(dir.write("idx.gltf", idx.gltf())),
            (dir.path() / "idx.gltf").string() +
                ": /accessors/4: index 7 (element 2) is out of range: the primitive has 3 vertices");
  // A buffer file that is not there.
  nlohmann::json missing = b.doc;
  missing["buffers"] = {{{"byteLength", b.bin.size()}, {"uri", "nothere.bin"}}};
  const std::string e = import_error(dir.write("missing.gltf", missing.dump()));
  EXPECT_NE(e.find("missing.gltf"), std::string::npos) << e;
  EXPECT_NE(e.find("nothere.bin"), std::string::npos) << e;
  // A node that is its own child.
  GltfBuilder cyc;
  cyc.triangle_node();
  cyc.doc["nodes"][0]["children"] = {0};
  cyc.doc["scenes"] = {{{"nodes", {0}}}};
  EXPECT_EQ(
      import_error(dir.write("cycle.gltf", cyc.gltf())),
      (dir.path() / "cycle.gltf").string() + ": /nodes/0: node is reached twice (the node hierarchy must be a tree)");
}

// A .glb with every kind of content, cut at every byte and with every byte overwritten: each either imports or
// throws InputError (tinygltf does not check everything itself; the importer's own checks must catch the rest).
TEST(Gltf, DamagedGlbNeverCrashes) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node({0, 0, 0, 1, 0, 0, 0, 1, 0}, 0);
  b.doc["images"] = {{{"bufferView", b.bytes_view(std::string("\x89PNG\r\n\x1a\n0123456789", 18))}}};
  b.doc["textures"] = {{{"source", 0}}};
  b.doc["materials"] = json::parse(R"([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}])");
  b.doc["extensions"]["KHR_lights_punctual"]["lights"] = {{{"type", "point"}}};
  b.doc["nodes"].push_back({{"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
  const std::string glb = b.glb();
  GltfImportOptions opt;
  opt.image_dir = dir.path() / "images";
  int ok = 0, errors = 0;
  const auto attempt = [&](const std::string& bytes) {
    const auto file = dir.write("d.glb", bytes);
    try {
      read_gltf(file, opt);
      ++ok;
    } catch (const InputError&) {
      ++errors;
    }
  };
  // Every other byte of the header and JSON chunk, every 4th of the binary chunk (under a second of CPU).
  const size_t bin_start = glb.size() - b.bin.size() - 8;
  for (size_t i = 0; i < glb.size(); i += i < bin_start ? 2 : 4) {
    attempt(glb.substr(0, i));
    std::string d = glb;
    d[i] = i % 2 ? '\xff' : '9';
    attempt(d);
  }
  fmt::print("{} bytes: {} damaged files imported, {} refused\n", glb.size(), ok, errors);
  EXPECT_GT(errors, int(bin_start / 2));  // every cut one at least
  EXPECT_GT(ok, 0);
}

// A gltf shape in a kozu scene: its primitives become meshes, its lights lights, its warning the scene's; a bad
// file is named under the shape's JSON path.
TEST(Gltf, ShapeInAScene) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node({0, 0, 0, 1, 0, 0, 0, 1, 0}, 0);
  b.doc["materials"] = {{{"emissiveFactor", {1, 1, 1}}, {"doubleSided", true}}};
  b.doc["extensionsUsed"] = {"KHR_lights_punctual", "KHR_materials_iridescence"};
  b.doc["extensions"]["KHR_lights_punctual"]["lights"] = {{{"type", "point"}, {"intensity", 683}}};
  b.doc["nodes"].push_back({{"translation", {0, 3, 0}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
  b.doc["scenes"] = {{{"nodes", {0, 1}}}};
  dir.write("m.glb", b.glb());
  const std::string scene = R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "resolution": [8, 8]},
    "shapes": [{"type": "gltf", "file": "m.glb", "transform": {"translate": [0, 1, 0]}}]})";
  SceneLoadOptions opt;
  opt.textures.convert_dir = dir.path() / "tx";
  const auto s = load_scene_text(scene, "s.json", dir.path(), opt);
  ASSERT_EQ(s->shapes.size(), 1u);
  EXPECT_EQ(s->triangle_count(), 1u);
  EXPECT_EQ(s->materials.size(), 1u);
  // The emissive triangle is an area light (two-sided, as the material is doubleSided: power 2π × area 1/2 × 1);
  // the point light too.
  ASSERT_EQ(s->lights.size(), 2u);
  EXPECT_NEAR(s->lights[0]->power().r, kPi, 1e-5f);
  ASSERT_FALSE(s->warnings.empty());
  EXPECT_EQ(s->warnings[0], "m.glb: not supported, ignored: KHR_materials_iridescence");
  Vec3 lo(kInfinity), hi(-kInfinity);  // bounds() grows the box it is given
  s->shapes[0]->bounds(lo, hi);
  expect_near(lo, Vec3(0, 1, 0));

  dir.write("bad.glb", "glTF");
  try {
    load_scene_text(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
      "shapes": [{"type": "gltf", "file": "bad.glb"}]})",
                    "s.json", dir.path(), opt);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("s.json: /shapes/0/file: " + (dir.path() / "bad.glb").string() + ": ", 0), 0u)
        << e.what();
  }
  // Materials come from the file.
  EXPECT_THROW(load_scene_text(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
      "shapes": [{"type": "gltf", "file": "m.glb", "material": "x"}]})",
                               "s.json", dir.path(), opt),
               InputError);
}

// A glTF file as a scene: its camera when it has one, else a camera framing its bounds, and a default environment
// when it has no light.
TEST(Gltf, FileAsASceneTakesItsCameraOrFramesIt) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node({-1, -1, 0, 1, -1, 0, 1, 1, 0});
  const auto plain = dir.write("plain.glb", b.glb());
  SceneLoadOptions opt;
  opt.textures.convert_dir = dir.path() / "tx";
  const auto s = load_gltf_file(plain, opt);
  EXPECT_EQ(s->lights.size(), 1u);
  EXPECT_TRUE(s->lights[0]->is_infinite());
  // The framing camera looks at the bounds' centre (0, 0, 0): the centre pixel's ray passes through it.
  const Ray r = s->camera.generate_ray(Vec2(0.5f, 0.5f) * Vec2(s->camera.resolution()), Vec2(0.5f));
  const Vec3 to_center = -r.o;
  EXPECT_NEAR(glm::dot(glm::normalize(to_center), glm::normalize(r.d)), 1.0f, 1e-3f);

  b.doc["cameras"] = {
      {{"type", "perspective"}, {"perspective", {{"yfov", 0.5}, {"znear", 0.1}, {"aspectRatio", 2.0}}}}};
  b.doc["nodes"].push_back({{"camera", 0}, {"translation", {0, 0, 7}}});
  b.doc["scenes"] = {{{"nodes", {0, 1}}}};
  const auto c = load_gltf_file(dir.write("cam.glb", b.glb()), opt);
  EXPECT_EQ(c->camera.resolution(), Vec2i(1440, 720));
  const Ray rc = c->camera.generate_ray(Vec2(720.0f, 360.0f), Vec2(0.5f));
  expect_near(rc.o, Vec3(0, 0, 7));
  expect_near(glm::normalize(rc.d), Vec3(0, 0, -1), 1e-3f);
}

std::string scene_error(const std::filesystem::path& file) {
  SceneLoadOptions opt;
  opt.textures.convert_dir = file.parent_path() / "tx";
  try {
    load_gltf_file(file, opt);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// A chain of 10,000 nodes, each the child of the one before, is walked without recursion (it overflowed the stack):
// the mesh at its end is placed by every translation on the way. Without `scenes`, a cycle of children is an error
// (it was rendered as an empty sky: no node of a cycle is a root).
TEST(Gltf, DeepNodeChainAndCyclesWithoutScenes) {
  TempDir dir;
  GltfBuilder b;
  const int n = 10000;
  b.triangle_node();  // node 0: the mesh, at the end of the chain
  for (int i = 1; i < n; ++i) b.doc["nodes"].push_back({{"children", {i - 1}}, {"translation", {0.001, 0, 0}}});
  b.doc["scenes"] = {{{"nodes", {n - 1}}}};
  const GltfScene s = import(dir, b, "chain.glb");
  ASSERT_EQ(s.primitives.size(), 1u);
  EXPECT_NEAR(s.primitives[0].mesh.positions[0].x, 0.001 * (n - 1), 1e-3);
  // The same chain without scenes: node n-1 is the only root.
  b.doc.erase("scenes");
  EXPECT_EQ(import(dir, b, "chain2.glb").primitives.size(), 1u);

  GltfBuilder cyc;
  cyc.triangle_node();
  cyc.doc["nodes"].push_back({{"children", {0}}});
  cyc.doc["nodes"][0]["children"] = {1};
  const auto file = dir.write("cycle.gltf", cyc.gltf());
  EXPECT_EQ(import_error(file), file.string() +
                                    ": /nodes/0/children: the node is part of a cycle of children (the node hierarchy "
                                    "must be a tree)");
}

// JSON nested deeper than the scene parser's limit (kMaxJsonDepth) is refused before tinygltf, whose recursive
// parser overflowed the stack on `extras` 30,000 deep: in a .gltf and in a .glb's JSON chunk, naming the path.
TEST(Gltf, DeepJsonIsRefusedBeforeTinygltf) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node();
  std::string text = b.gltf();
  ASSERT_EQ(text.back(), '}');
  text.pop_back();
  text += ",\"extras\":{\"a\":" + std::string(30000, '[') + std::string(30000, ']') + "}}";
  const std::string expect =
      ": /extras/a/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/"
      "0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0: arrays and objects nested deeper "
      "than 64 levels";
  const auto gltf = dir.write("deep.gltf", text);
  EXPECT_EQ(import_error(gltf), gltf.string() + expect);
  const auto glb = dir.write(
      "deep.glb",
      GltfBuilder::glb_from(text.substr(0, text.find(",\"buffers\"")) + text.substr(text.find(",\"extras\"")), b.bin));
  EXPECT_EQ(import_error(glb), glb.string() + expect);
  // 64 levels are allowed.
  std::string ok = b.gltf();
  ok.pop_back();
  ok += ",\"extras\":" + std::string(63, '[') + std::string(63, ']') + "}";
  EXPECT_EQ(import_error(dir.write("ok.gltf", ok)), "");
}

// Accessors are checked whole before anything is allocated (an unused one too), and the memory the meshes take is
// estimated first: a 2 KB file whose primitives all read a 2^26-element accessor of zeros asked for over 40 GB.
TEST(Gltf, MemoryIsEstimatedBeforeAllocating) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node();
  GltfBuilder unused = b;
  unused.doc["accessors"].push_back({{"bufferView", 0}, {"componentType", 5126}, {"count", 1000}, {"type", "VEC3"}});
  const auto u = dir.write("unused.gltf", unused.gltf());
  EXPECT_EQ(import_error(u), u.string() +
                                 ": /accessors/4: byteOffset 0 with 1000 elements of stride 12 exceeds "
                                 "bufferView 0 (36 bytes)");

  GltfBuilder big = b;
  big.doc["accessors"].push_back({{"componentType", 5126}, {"count", 1 << 26}, {"type", "VEC3"}});
  const int zeros = int(big.doc["accessors"].size()) - 1;
  json prim = {{"attributes", {{"POSITION", zeros}, {"NORMAL", zeros}}}};
  big.doc["meshes"][0]["primitives"] = json::array();
  for (int i = 0; i < 40; ++i) big.doc["meshes"][0]["primitives"].push_back(prim);
  const std::string text = big.gltf();
  EXPECT_LT(text.size(), 4000u);
  const auto f = dir.write("big.gltf", text);
  const MemoryLimitEnv limit(size_t(2) << 30);
  const size_t peak = peak_rss_bytes();
  const std::string e = import_error(f);
  EXPECT_EQ(e.rfind(f.string() + ": /meshes: the meshes need about ", 0), 0u) << e;
  EXPECT_NE(e.find("KOZU_MEMORY_LIMIT"), std::string::npos) << e;
  EXPECT_LT(peak_rss_bytes(), peak + (size_t(256) << 20));
}

// An external image is probed, not read (the texture cache reads it once, later), after a size check: a 1 GiB image
// file was read whole, twice. One larger than kozu reads is refused at its URI.
TEST(Gltf, ImageFilesAreSizeCheckedAndNotReadWhole) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node({0, 0, 0, 1, 0, 0, 0, 1, 0}, 0);
  b.doc["images"] = {{{"uri", "big.png"}}};
  b.doc["textures"] = {{{"source", 0}}};
  b.doc["materials"] = json::parse(R"([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}])");
  const auto make_sparse = [&](const std::string& name, uint64_t size) {
    const auto p = dir.write(name, std::string("\x89PNG\r\n\x1a\n", 8));
    std::filesystem::resize_file(p, size);
  };
  make_sparse("big.png", uint64_t(1) << 30);
  const auto f = dir.write("img.gltf", b.gltf());
  const size_t peak = peak_rss_bytes();
  const GltfScene s = read_gltf(f);
  EXPECT_LT(peak_rss_bytes(), peak + (size_t(256) << 20));
  EXPECT_EQ(s.materials[0]["base_color"]["file"], (dir.path() / "big.png").lexically_normal().string());

  make_sparse("huge.png", (uint64_t(8) << 30) + 1);
  b.doc["images"][0]["uri"] = "huge.png";
  const auto h = dir.write("huge.gltf", b.gltf());
  const std::string e = import_error(h);
  EXPECT_EQ(e.rfind(h.string() + ": /images/0/uri: ", 0), 0u) << e;
  EXPECT_NE(e.find("kozu reads at most 8.0 GiB"), std::string::npos) << e;
}

// Stored triangles: those of the meshes and of each distinct instanced object once.
size_t stored_triangles(const Scene& s) {
  size_t n = 0;
  std::set<const InstancedObject*> objects;
  for (const auto& shape : s.shapes) {
    if (const auto* inst = dynamic_cast<const Instance*>(shape.get())) {
      if (objects.insert(&inst->object()).second)
        for (const auto& o : inst->object().shapes()) n += o->primitive_count();
    } else {
      n += shape->primitive_count();
    }
  }
  return n;
}

// 400 nodes of one mesh keep one mesh, placed by Embree instances (they were 400 copies: 5.6 GB and 138 s for a
// large mesh), and render the image of the copies.
TEST(Gltf, SharedMeshesBecomeInstances) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node({-1, -1, 0, 1, -1, 0, 0, 1, 0});
  b.doc["nodes"][0]["translation"] = {-1.5, 0, 0};
  for (int i = 1; i < 400; ++i)
    b.doc["nodes"].push_back({{"mesh", 0}, {"translation", {-1.5 + 3.0 * (i % 2), 0, -0.01 * i}}});
  const GltfScene s = import(dir, b, "inst.glb");
  EXPECT_TRUE(s.primitives.empty());
  ASSERT_EQ(s.objects.size(), 1u);
  EXPECT_EQ(s.instances.size(), 400u);
  expect_near(Vec3(s.instances[1].transform[3]), Vec3(1.5, 0, -0.01f));

  // The same nodes, each with a mesh of its own (copies), render the same image.
  GltfBuilder c = b;
  for (int i = 1; i < 400; ++i) {
    c.doc["meshes"].push_back(c.doc["meshes"][0]);
    c.doc["nodes"][i]["mesh"] = i;
  }
  dir.write("inst.glb", b.glb());
  dir.write("copies.glb", c.glb());
  const auto scene = [](const char* file) {
    return fmt::format(R"({{"camera": {{"position": [0, 0, 6], "look_at": [0, 0, 0], "resolution": [24, 16]}},
      "shapes": [{{"type": "gltf", "file": "{}"}}], "lights": [{{"type": "environment", "radiance": 1}}]}})",
                       file);
  };
  const TestRender inst = render_json(scene("inst.glb"), 4, 1, 7, dir.path());
  const TestRender copies = render_json(scene("copies.glb"), 4, 1, 7, dir.path());
  EXPECT_EQ(stored_triangles(*inst.scene), 1u);
  EXPECT_EQ(stored_triangles(*copies.scene), 400u);
  EXPECT_EQ(inst.scene->triangle_count(), 400u);  // the triangles the image shows
  double diff = 0.0;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 24; ++x)
      diff = std::max(diff, double(max_component(glm::abs(inst.film.mean(x, y) - copies.film.mean(x, y)))));
  EXPECT_LT(diff, 1e-3);
  EXPECT_LT(image_stats(inst.film).mean.r, 0.999f);  // the triangles are in the image
}

// What a kozu scene refuses is refused in a glTF, at the glTF's JSON path.
TEST(Gltf, ValuesKozuRefusesAreRefusedWithTheGltfPath) {
  TempDir dir;
  const auto expect_error = [&](GltfBuilder& b, const std::string& name, const std::string& message) {
    const auto f = dir.write(name, name.ends_with(".glb") ? b.glb() : b.gltf());
    EXPECT_EQ(import_error(f), f.string() + ": " + message);
  };
  GltfBuilder cam;
  cam.triangle_node();
  cam.doc["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", 0.7}, {"znear", 0.1}}}}};
  cam.doc["nodes"].push_back({{"camera", 0}, {"translation", {1e20, 0, 0}}});
  expect_error(cam, "far.gltf",
               "/nodes/1: the camera's position: coordinates must lie within ±1e+15, got (1e+20, 0, 0)");
  cam.doc["nodes"][1]["translation"] = {0, 0, 5};
  cam.doc["cameras"][0]["perspective"]["aspectRatio"] = 1e9;
  expect_error(cam, "wide.gltf",
               "/cameras/0/perspective/aspectRatio: aspect ratio 1e+09 gives an image 7.2e+11 pixels wide and 720 "
               "high; kozu renders widths from 1 to 65536 (aspect ratios 0.000694 to 91)");
  cam.doc["cameras"][0]["perspective"]["aspectRatio"] = 1e-9;
  expect_error(cam, "narrow.gltf",
               "/cameras/0/perspective/aspectRatio: aspect ratio 1e-09 gives an image 0 pixels wide and 720 high; "
               "kozu renders widths from 1 to 65536 (aspect ratios 0.000694 to 91)");

  GltfBuilder m;
  m.triangle_node();
  m.doc["nodes"][0]["matrix"] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0.5, 0, 0, 0, 1};
  expect_error(m, "proj.gltf",
               "/nodes/0/matrix: the matrix is not affine: its last row is (0, 0, 0.5, 1), not (0, 0, 0, 1)");

  GltfBuilder v3;
  v3.triangle_node();
  const auto f3 = dir.write("v3.glb", GltfBuilder::glb_from(v3.doc.dump(), v3.bin, 3));
  EXPECT_EQ(import_error(f3), f3.string() + ": GLB version 3: kozu reads version 2 (glTF 2.0) only");

  GltfBuilder neg;
  neg.triangle_node();
  neg.doc["bufferViews"][1]["byteOffset"] = -8;
  expect_error(neg, "neg.gltf", "/bufferViews/1/byteOffset: byteOffset must be >= 0, got -8");
  neg.doc["bufferViews"][1]["byteOffset"] = 36;
  neg.doc["bufferViews"][1]["byteLength"] = -36;
  expect_error(neg, "neglen.glb", "/bufferViews/1/byteLength: byteLength must be >= 0, got -36");

  // Negative emission gave NaN samples.
  GltfBuilder e;
  e.triangle_node({0, 0, 0, 1, 0, 0, 0, 1, 0}, 0);
  e.doc["materials"] = {{{"emissiveFactor", {1, -0.5, 1}}}};
  expect_error(e, "negemit.gltf", "/materials/0/emissiveFactor/1: expected a number >= 0, got -0.5");
  e.doc["materials"][0]["emissiveFactor"] = {1, 1, 1};
  e.doc["materials"][0]["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"] = -2;
  expect_error(
      e, "negstrength.gltf",
      "/materials/0/extensions/KHR_materials_emissive_strength/emissiveStrength: expected a number >= 0, got -2");
  // An emitter whose power overflows: radiance 1e20 over a triangle scaled by 1e8 (area 5e15).
  e.doc["materials"][0]["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"] = 1e20;
  e.doc["nodes"][0]["scale"] = {1e8, 1e8, 1};
  const auto fp = dir.write("power.gltf", e.gltf());
  const std::string ep = import_error(fp);
  EXPECT_EQ(ep.rfind(fp.string() + ": /materials/0/extensions/KHR_materials_emissive_strength/emissiveStrength: the "
                                   "emitter's power (1.57e+36 W",
                     0),
            0u)
      << ep;

  // A light's intensity beyond range, at its glTF path.
  GltfBuilder l;
  l.triangle_node();
  l.doc["extensions"]["KHR_lights_punctual"]["lights"] = {{{"type", "point"}, {"intensity", 1e40}}};
  l.doc["nodes"].push_back({{"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
  expect_error(l, "light.gltf",
               "/extensions/KHR_lights_punctual/lights/0/intensity: intensity 1e+40 is beyond kozu's range (a "
               "light's power is at most 1e+30)");

  // A file that yields no triangle is an error, not an empty sky.
  GltfBuilder none;
  none.triangle_node({0, 0, 0, 1, 0, 0, 2, 0, 0});  // zero area
  const auto fn = dir.write("flat.glb", none.glb());
  EXPECT_EQ(scene_error(fn), fn.string() +
                                 ": the file yields no triangle to render (its scene's meshes are missing, points or "
                                 "lines only, or of zero area)");
  GltfBuilder empty;
  const auto fe = dir.write("empty.gltf", empty.gltf());
  EXPECT_NE(scene_error(fe).find("yields no triangle"), std::string::npos) << scene_error(fe);
}

// Messages about the kozu descriptions the import writes name the glTF's keys: a texture whose image cannot be read
// names /images/N/uri (it named /materials/0/base_color/file), and GltfScene::gltf_path maps kozu's keys.
TEST(Gltf, MessagesNameTheGltfPath) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node({0, 0, 0, 1, 0, 0, 0, 1, 0}, 0);
  b.doc["images"] = {{{"uri", "notanimage.png"}}};
  b.doc["textures"] = {{{"source", 0}}};
  b.doc["materials"] = json::parse(R"([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}},
    "extensions": {"KHR_materials_specular": {"specularColorFactor": [0.5, 0.5, 0.25]}}}])");
  dir.write("notanimage.png", "this is text");
  const auto f = dir.write("m.gltf", b.gltf());
  const std::string e = scene_error(f);
  EXPECT_EQ(e.rfind(f.string() + ": /images/0/uri: ", 0), 0u) << e;
  const GltfScene s = read_gltf(f);
  EXPECT_EQ(s.gltf_path("/materials/0/specular_color/2"),
            "/materials/0/extensions/KHR_materials_specular/specularColorFactor/2");
  EXPECT_EQ(s.gltf_path("/materials/0/base_color/file"), "/images/0/uri");
  EXPECT_EQ(s.gltf_path("/materials/0/base_color/scale/1"), "/materials/0/pbrMetallicRoughness/baseColorFactor/1");
  EXPECT_EQ(s.gltf_path("/materials/0/roughness"), "/materials/0/pbrMetallicRoughness/roughnessFactor");
}

// Blender 3.4 writes specularColorFactor above 1 (legal: the schema has no maximum) and the file was refused. kozu
// uses the product specular × specular_color: a colour above 1 is carried into the factor, exactly while the
// product stays within 1, and the rest is clamped with one warning for the file.
TEST(Gltf, LegalValuesBeyondTheModelAreClampedWithOneWarning) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node({0, 0, 0, 1, 0, 0, 0, 1, 0}, 0);
  b.doc["materials"] = json::parse(R"([
    {"extensions": {"KHR_materials_specular": {"specularFactor": 0.5, "specularColorFactor": [1.2, 1.0, 0.6]}}},
    {"extensions": {"KHR_materials_specular": {"specularColorFactor": [2.0, 2.0, 2.0]},
                    "KHR_materials_ior": {"ior": 4.5}},
     "normalTexture": {"index": 0, "scale": -1}}])");
  b.doc["images"] = {{{"uri", "n.png"}}};
  b.doc["textures"] = {{{"source", 0}}};
  b.doc["meshes"].push_back(b.doc["meshes"][0]);
  b.doc["meshes"][1]["primitives"][0]["material"] = 1;
  b.doc["nodes"].push_back({{"mesh", 1}});
  dir.write("n.png", std::string("\x89PNG\r\n\x1a\n", 8));
  const GltfScene s = import(dir, b, "blender.gltf");
  EXPECT_NEAR(s.materials[0]["specular"].get<double>(), 0.6, 1e-12);
  EXPECT_NEAR(s.materials[0]["specular_color"][0].get<double>(), 1.0, 1e-12);
  EXPECT_NEAR(s.materials[0]["specular_color"][2].get<double>(), 0.5, 1e-12);
  EXPECT_FALSE(s.materials[1].contains("specular"));  // 2 × 1 clamped to 1, kozu's default
  EXPECT_FALSE(s.materials[1].contains("specular_color"));
  EXPECT_EQ(s.materials[1]["ior"], 3.0);
  EXPECT_EQ(s.materials[1].value("normal_map_strength", 1.0), 0.0);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_EQ(s.warnings[0],
            "blender.gltf: values beyond what kozu's models represent were clamped: "
            "/materials/1/extensions/KHR_materials_ior/ior 4.5 → 3, "
            "/materials/1/extensions/KHR_materials_specular/specularColorFactor 2 → 1, "
            "/materials/1/normalTexture/scale -1 → 0");
}

// The files a glTF reads are inputs of the render (Scene::input_files): an output may not overwrite its buffer or
// its textures.
TEST(Gltf, BuffersAndImagesAreInputFiles) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node({0, 0, 0, 1, 0, 0, 0, 1, 0}, 0);
  b.doc["images"] = {{{"uri", "tex.png"}}};
  b.doc["textures"] = {{{"source", 0}}};
  b.doc["materials"] = json::parse(R"([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}])");
  const std::string png = rgba_png(dir);
  dir.write("tex.png", png);
  dir.write("m.bin", b.bin);
  const auto f = dir.write("m.gltf", b.gltf_external("m.bin"));
  SceneLoadOptions opt;
  opt.textures.convert_dir = dir.path() / "tx";
  const auto s = load_gltf_file(f, opt);
  std::set<std::filesystem::path> inputs;
  for (const auto& p : s->input_files) inputs.insert(std::filesystem::weakly_canonical(p));
  EXPECT_TRUE(inputs.count(std::filesystem::weakly_canonical(dir.path() / "m.bin")));
  EXPECT_TRUE(inputs.count(std::filesystem::weakly_canonical(dir.path() / "tex.png")));
  EXPECT_TRUE(inputs.count(std::filesystem::weakly_canonical(f)));
}

}  // namespace
}  // namespace kozu::test
