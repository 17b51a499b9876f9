#include "io/checkpoint_file.h"

#include "core/error.h"
#include "core/file_io.h"
#include "core/temp_files.h"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace kozu {

namespace {

constexpr char kMagic[8] = {'K', 'O', 'Z', 'U', 'C', 'K', 'P', 'T'};

void put_u32(std::ostream& out, uint32_t v) {
  unsigned char b[4];
  for (int i = 0; i < 4; ++i) b[i] = static_cast<unsigned char>(v >> (8 * i));
  out.write(reinterpret_cast<const char*>(b), 4);
}
void put_u64(std::ostream& out, uint64_t v) {
  unsigned char b[8];
  for (int i = 0; i < 8; ++i) b[i] = static_cast<unsigned char>(v >> (8 * i));
  out.write(reinterpret_cast<const char*>(b), 8);
}

}  // namespace

uint64_t hash_words(const void* data, uint64_t bytes, uint64_t h) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (uint64_t i = 0; i < bytes; i += 8) {
    uint64_t w = 0;
    const uint64_t n = std::min<uint64_t>(8, bytes - i);
    for (uint64_t k = 0; k < n; ++k) w |= uint64_t{p[i + k]} << (8 * k);
    h = (h ^ w) * 0x100000001b3ull;
  }
  return h;
}

void WordHasher::update(const void* data, uint64_t bytes) {
  const auto* p = static_cast<const unsigned char*>(data);
  // Complete a word begun by the last piece, then whole words, then keep the rest.
  while (tail_bytes_ > 0 && tail_bytes_ < 8 && bytes > 0) {
    tail_[tail_bytes_++] = *p++;
    --bytes;
  }
  if (tail_bytes_ == 8) {
    h_ = hash_words(tail_, 8, h_);
    tail_bytes_ = 0;
  }
  const uint64_t whole = bytes / 8 * 8;
  h_ = hash_words(p, whole, h_);
  for (uint64_t i = whole; i < bytes; ++i) tail_[tail_bytes_++] = p[i];
}

uint64_t WordHasher::digest() const { return tail_bytes_ ? hash_words(tail_, tail_bytes_, h_) : h_; }

void write_checkpoint_file(const std::filesystem::path& file, const nlohmann::json& header, const void* payload,
                           uint64_t payload_bytes, uint32_t format) {
  write_checkpoint_file(
      file, header, payload_bytes, [&](const PayloadPut& put) { put(payload, payload_bytes); }, format);
}

void write_checkpoint_file(const std::filesystem::path& file, const nlohmann::json& header, uint64_t payload_bytes,
                           const std::function<void(const PayloadPut&)>& produce, uint32_t format) {
  const std::string text = header.dump();
  if (text.size() > kMaxCheckpointHeaderBytes)
    throw std::runtime_error(fmt::format("{}: checkpoint header too large ({} bytes)", file.string(), text.size()));
  const std::filesystem::path dir = file.parent_path();
  if (!dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw std::runtime_error(fmt::format("{}: cannot create folder: {}", dir.string(), ec.message()));
  }
  TempFileGuard tmp(temp_path_for(file));
  {
    errno = 0;
    std::ofstream out;
    create_temp_file([&] { out.open(tmp.path(), std::ios::binary); });
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write: {}", file.string(), errno_message(errno)));
    out.write(kMagic, sizeof kMagic);
    put_u32(out, format);
    put_u32(out, static_cast<uint32_t>(text.size()));
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    put_u64(out, payload_bytes);
    WordHasher hash;
    uint64_t written = 0;
    produce([&](const void* data, size_t bytes) {
      if (bytes > payload_bytes - written) throw std::logic_error("write_checkpoint_file: more bytes than promised");
      out.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
      hash.update(data, bytes);
      written += bytes;
    });
    if (written != payload_bytes) throw std::logic_error("write_checkpoint_file: fewer bytes than promised");
    put_u64(out, hash.digest());
    out.flush();
    if (!out) throw std::runtime_error(fmt::format("{}: write failed: {}", file.string(), errno_message(errno)));
  }
  rename_into_place(tmp, file);
}

CheckpointFileReader::CheckpointFileReader(const std::filesystem::path& file)
    : file_(file), in_(open_input_file(file)) {
  const auto fail = [&](const std::string& message) -> void {
    throw InputError(file.string(), "", "not a kozu checkpoint: " + message);
  };
  std::error_code ec;
  const uint64_t size = std::filesystem::file_size(file, ec);
  if (ec) fail("cannot read its size: " + ec.message());
  uint64_t pos = 0;
  const auto read = [&](void* dst, uint64_t n, const char* what) {
    if (n > size - pos) fail(fmt::format("the file ends inside {} (byte {} of {})", what, pos, size));
    in_.read(static_cast<char*>(dst), static_cast<std::streamsize>(n));
    if (!in_) fail(fmt::format("cannot read {} at byte {}", what, pos));
    pos += n;
  };
  const auto u64 = [&](const char* what) {
    unsigned char b[8];
    read(b, 8, what);
    uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= uint64_t{b[i]} << (8 * i);
    return v;
  };
  const auto u32 = [&](const char* what) {
    unsigned char b[4];
    read(b, 4, what);
    return uint32_t{b[0]} | (uint32_t{b[1]} << 8) | (uint32_t{b[2]} << 16) | (uint32_t{b[3]} << 24);
  };
  char magic[8];
  read(magic, 8, "the magic number");
  if (std::memcmp(magic, kMagic, 8) != 0) fail("bad magic number");
  format_ = u32("the format number");
  if (format_ < kOldestCheckpointFormat || format_ > kCheckpointFormat)
    throw InputError(file.string(), "",
                     fmt::format("checkpoint format {} is not one this kozu reads ({} to {})", format_,
                                 kOldestCheckpointFormat, kCheckpointFormat));
  const uint32_t header_bytes = u32("the header length");
  if (header_bytes > kMaxCheckpointHeaderBytes) fail(fmt::format("header of {} bytes", header_bytes));
  std::string text(header_bytes, '\0');
  read(text.data(), header_bytes, "the header");
  header_ = nlohmann::json::parse(text, nullptr, false);
  if (header_.is_discarded() || !header_.is_object()) fail("the header is not a JSON object");
  payload_bytes_ = u64("the payload length");
  if (size - pos < 8 || payload_bytes_ != size - pos - 8)
    fail(fmt::format("the header promises {} bytes of samples but the file holds {} (truncated?)", payload_bytes_,
                     size - pos >= 8 ? size - pos - 8 : 0));
}

void CheckpointFileReader::read_payload(void* dst) {
  read(dst, payload_bytes_);
  finish();
}

void CheckpointFileReader::read(void* dst, uint64_t bytes) {
  if (bytes > payload_bytes_ - consumed_) throw std::logic_error("CheckpointFileReader: read past the payload");
  const auto fail = [&] { throw InputError(file_.string(), "", "cannot read the checkpoint's samples"); };
  if (dst) {
    in_.read(static_cast<char*>(dst), static_cast<std::streamsize>(bytes));
    if (!in_) fail();
    hash_.update(dst, bytes);
  } else {
    char scratch[1 << 16];
    for (uint64_t left = bytes; left > 0;) {
      const uint64_t n = std::min<uint64_t>(left, sizeof scratch);
      in_.read(scratch, static_cast<std::streamsize>(n));
      if (!in_) fail();
      hash_.update(scratch, n);
      left -= n;
    }
  }
  consumed_ += bytes;
}

void CheckpointFileReader::finish() {
  if (consumed_ != payload_bytes_) throw std::logic_error("CheckpointFileReader: finished before the payload's end");
  unsigned char b[8];
  in_.read(reinterpret_cast<char*>(b), 8);
  if (!in_) throw InputError(file_.string(), "", "cannot read the checkpoint's samples");
  uint64_t stored = 0;
  for (int i = 0; i < 8; ++i) stored |= uint64_t{b[i]} << (8 * i);
  if (stored != hash_.digest())
    throw InputError(file_.string(), "", "the checkpoint's samples are damaged (their hash does not match)");
}

}  // namespace kozu
