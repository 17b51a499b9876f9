// kozu's checkpoint container (`kozu render --checkpoint`): a small JSON header that says what the file belongs to,
// then a raw payload (a film's accumulators), then a hash of the payload. Layout, little-endian:
//   "KOZUCKPT"  u32 format (kCheckpointFormat)  u32 header bytes  header (JSON text)  u64 payload bytes  payload
//   u64 hash (64-bit FNV-1a over the payload's 8-byte words)
// Every length is checked against the file's size before anything is allocated, and the hash catches a truncated
// or damaged payload, so a bad file is refused with a message instead of resuming from garbage.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>

namespace kozu {

// 2: the features (Film::FeaturePixel) carry the visible emission.
// 3: the features lose their sample count (the pixel's samples taken) and their position, which follows them only
//    when the render keeps it (`--aov position`); format 2 is still read.
inline constexpr uint32_t kCheckpointFormat = 3;
inline constexpr uint32_t kOldestCheckpointFormat = 2;
inline constexpr uint32_t kMaxCheckpointHeaderBytes = 1 << 16;

// Writes the file atomically (a temporary file renamed into place). Throws std::runtime_error naming the file.
// `format`: another than kCheckpointFormat only to test the reading of older files.
void write_checkpoint_file(const std::filesystem::path& file, const nlohmann::json& header, const void* payload,
                           uint64_t payload_bytes, uint32_t format = kCheckpointFormat);

// Reads the header at construction; the payload on request, once the caller has checked the header.
// Throws InputError(file, "", reason) for anything that is not a whole checkpoint of this format.
class CheckpointFileReader {
 public:
  explicit CheckpointFileReader(const std::filesystem::path& file);
  const nlohmann::json& header() const { return header_; }
  uint64_t payload_bytes() const { return payload_bytes_; }
  uint32_t format() const { return format_; }  // kOldestCheckpointFormat .. kCheckpointFormat
  // Reads exactly payload_bytes() into dst and checks its hash.
  void read_payload(void* dst);

 private:
  std::filesystem::path file_;
  std::ifstream in_;
  nlohmann::json header_;
  uint64_t payload_bytes_ = 0;
  uint32_t format_ = 0;
};

// 64-bit FNV-1a over 8-byte little-endian words (a byte tail is padded with zeros).
uint64_t hash_words(const void* data, uint64_t bytes, uint64_t h = 0xcbf29ce484222325ull);

}  // namespace kozu
