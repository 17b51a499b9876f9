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
#include <functional>

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
// The same with the payload given in pieces, so that it need not be in memory at once: produce(put) calls put(data,
// bytes) with the pieces in order, payload_bytes in all (std::logic_error otherwise).
using PayloadPut = std::function<void(const void* data, size_t bytes)>;
void write_checkpoint_file(const std::filesystem::path& file, const nlohmann::json& header, uint64_t payload_bytes,
                           const std::function<void(const PayloadPut&)>& produce,
                           uint32_t format = kCheckpointFormat);

// 64-bit FNV-1a over 8-byte little-endian words (a byte tail is padded with zeros).
uint64_t hash_words(const void* data, uint64_t bytes, uint64_t h = 0xcbf29ce484222325ull);

// hash_words over a byte stream given in pieces of any size: the digest equals hash_words over their concatenation.
class WordHasher {
 public:
  void update(const void* data, uint64_t bytes);
  uint64_t digest() const;

 private:
  uint64_t h_ = 0xcbf29ce484222325ull;
  unsigned char tail_[8] = {};
  int tail_bytes_ = 0;  // bytes of a word not yet complete
};

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
  // The payload in pieces instead, in order: the next `bytes` into dst (null: skipped, still hashed); finish(), once
  // all of it was read, checks the hash. Reading past the payload is a std::logic_error.
  void read(void* dst, uint64_t bytes);
  void finish();

 private:
  std::filesystem::path file_;
  std::ifstream in_;
  nlohmann::json header_;
  uint64_t payload_bytes_ = 0;
  uint32_t format_ = 0;
  uint64_t consumed_ = 0;  // payload bytes read so far
  WordHasher hash_;
};

}  // namespace kozu
