// SHA-256 (FIPS 180-4) of bytes and files, as lowercase hex: the content hashes of batch manifests
// (an item is redone when its input, graph or settings hash changes; outputs are recorded by hash
// so two runs can be compared byte for byte). Written here because none of the project's Debian
// dependencies offers a public hash API.
//
//   std::string h = sha256_hex("abc");   // "ba7816bf..."
//   Sha256 s; s.update(a); s.update(b); std::string h2 = s.hex();
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace kg::graph {

class Sha256 {
 public:
  Sha256();
  void update(const void* data, std::size_t size);
  void update(std::string_view bytes) { update(bytes.data(), bytes.size()); }
  // The digest of everything updated so far, as 64 lowercase hex digits. Ends the hash: call once.
  std::string hex();

 private:
  void compress(const std::uint8_t* block);
  std::array<std::uint32_t, 8> state_;
  std::array<std::uint8_t, 64> buffer_{};
  std::size_t buffered_ = 0;
  std::uint64_t total_bytes_ = 0;
};

std::string sha256_hex(std::string_view bytes);

// The hash of a file's content, read in blocks. Throws std::runtime_error naming the file when it
// cannot be read.
std::string sha256_file(const std::filesystem::path& file);

}  // namespace kg::graph
