// SHA-256 (FIPS 180-4) of bytes and files, as lowercase hex: the content hashes of batch manifests
// (an item is redone when its input, graph or settings hash changes; outputs are recorded by hash
// so two runs can be compared byte for byte). Computed by OpenSSL's EVP interface (libcrypto).
//
//   std::string h = sha256_hex("abc");   // "ba7816bf..."
//   Sha256 s; s.update(a); s.update(b); std::string h2 = s.hex();
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

struct evp_md_ctx_st;  // OpenSSL's EVP_MD_CTX, kept out of this header

namespace kg::graph {

// A hash in progress. Copying it copies the state (both go on from the bytes updated so far).
class Sha256 {
 public:
  Sha256();
  Sha256(const Sha256& other);
  Sha256& operator=(const Sha256& other);
  Sha256(Sha256&&) noexcept = default;
  Sha256& operator=(Sha256&&) noexcept = default;
  ~Sha256();

  void update(const void* data, std::size_t size);
  void update(std::string_view bytes) { update(bytes.data(), bytes.size()); }
  // The digest of everything updated so far, as 64 lowercase hex digits. Ends the hash: call once.
  std::string hex();

 private:
  struct FreeContext {
    void operator()(evp_md_ctx_st* context) const;
  };
  std::unique_ptr<evp_md_ctx_st, FreeContext> context_;  // owned
};

std::string sha256_hex(std::string_view bytes);

// The hash of a file's content, read in blocks. Throws std::runtime_error naming the file when it
// cannot be read.
std::string sha256_file(const std::filesystem::path& file);

}  // namespace kg::graph
