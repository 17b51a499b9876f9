// Small glTF files written by the tests themselves: a JSON document whose one buffer is a base64 data URI (or the
// BIN chunk of a .glb), filled from typed arrays.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace kozu::test {

inline std::string base64(const std::string& bytes) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v =
        (uint32_t(uint8_t(bytes[i])) << 16) | (uint32_t(uint8_t(bytes[i + 1])) << 8) | uint8_t(bytes[i + 2]);
    out += {k[v >> 18], k[(v >> 12) & 63], k[(v >> 6) & 63], k[v & 63]};
  }
  if (i + 1 == bytes.size()) {
    const uint32_t v = uint32_t(uint8_t(bytes[i])) << 16;
    out += {k[v >> 18], k[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const uint32_t v = (uint32_t(uint8_t(bytes[i])) << 16) | (uint32_t(uint8_t(bytes[i + 1])) << 8);
    out += {k[v >> 18], k[(v >> 12) & 63], k[(v >> 6) & 63], '='};
  }
  return out;
}

// Builds the buffer, buffer views and accessors of a glTF document.
class GltfBuilder {
 public:
  nlohmann::json doc = {{"asset", {{"version", "2.0"}}}};

  // An accessor over new bytes: floats of `type` ("VEC3", "SCALAR", …), 4-byte aligned.
  int floats(const std::vector<float>& v, const std::string& type) {
    return add(v.data(), v.size() * 4, 5126, type, count(v.size(), type));
  }
  int indices(const std::vector<uint16_t>& v) { return add(v.data(), v.size() * 2, 5123, "SCALAR", v.size()); }
  int indices32(const std::vector<uint32_t>& v) { return add(v.data(), v.size() * 4, 5125, "SCALAR", v.size()); }
  // A buffer view holding raw bytes (an image).
  int bytes_view(const std::string& b) {
    const size_t offset = append(b.data(), b.size());
    doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", b.size()}});
    return int(doc["bufferViews"].size()) - 1;
  }
  // The document with its buffer as a data URI (.gltf).
  std::string gltf() {
    nlohmann::json d = doc;
    if (bin.empty()) return d.dump();  // no buffer (a file of lights only)
    d["buffers"] = {{{"byteLength", bin.size()}, {"uri", "data:application/octet-stream;base64," + base64(bin)}}};
    return d.dump();
  }
  // The document with its buffer in a file of its own (`bin_name`, relative to the .gltf), whose bytes are `bin`.
  std::string gltf_external(const std::string& bin_name) {
    nlohmann::json d = doc;
    d["buffers"] = {{{"byteLength", bin.size()}, {"uri", bin_name}}};
    return d.dump();
  }
  // The document as a binary .glb (header, JSON chunk, BIN chunk; §4.4).
  std::string glb() {
    nlohmann::json d = doc;
    if (!bin.empty()) d["buffers"] = {{{"byteLength", bin.size()}}};
    return glb_from(d.dump(), bin);
  }
  // A .glb of the given JSON text and binary chunk (empty: none), of container version `version`.
  static std::string glb_from(std::string json, std::string b, uint32_t version = 2) {
    while (json.size() % 4) json += ' ';
    while (b.size() % 4) b += '\0';
    std::string out;
    auto u32 = [&out](uint32_t x) { out.append(reinterpret_cast<const char*>(&x), 4); };
    out += "glTF";
    u32(version);
    u32(uint32_t(12 + 8 + json.size() + (b.empty() ? 0 : 8 + b.size())));
    u32(uint32_t(json.size()));
    out += "JSON";
    out += json;
    if (!b.empty()) {
      u32(uint32_t(b.size()));
      out += std::string("BIN\0", 4);
      out += b;
    }
    return out;
  }
  // A one-triangle mesh (positions, normals, TEXCOORD_0, indices) and a node holding it; returns the node.
  int triangle_node(const std::vector<float>& positions = {0, 0, 0, 1, 0, 0, 0, 1, 0}, int material = -1) {
    nlohmann::json prim = {{"attributes",
                            {{"POSITION", floats(positions, "VEC3")},
                             {"NORMAL", floats({0, 0, 1, 0, 0, 1, 0, 0, 1}, "VEC3")},
                             {"TEXCOORD_0", floats({0.25f, 0.1f, 1, 0, 0, 1}, "VEC2")}}},
                           {"indices", indices({0, 1, 2})}};
    if (material >= 0) prim["material"] = material;
    doc["meshes"].push_back({{"primitives", {prim}}});
    doc["nodes"].push_back({{"mesh", int(doc["meshes"].size()) - 1}});
    return int(doc["nodes"].size()) - 1;
  }

  std::string bin;

 private:
  static size_t count(size_t n, const std::string& type) {
    return type == "SCALAR" ? n : type == "VEC2" ? n / 2 : type == "VEC3" ? n / 3 : type == "VEC4" ? n / 4 : n / 16;
  }
  size_t append(const void* p, size_t n) {
    while (bin.size() % 4) bin += '\0';
    const size_t offset = bin.size();
    bin.append(static_cast<const char*>(p), n);
    return offset;
  }
  int add(const void* p, size_t n, int component, const std::string& type, size_t elements) {
    const size_t offset = append(p, n);
    doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", n}});
    doc["accessors"].push_back({{"bufferView", int(doc["bufferViews"].size()) - 1},
                                {"componentType", component},
                                {"count", elements},
                                {"type", type}});
    return int(doc["accessors"].size()) - 1;
  }
};

}  // namespace kozu::test
