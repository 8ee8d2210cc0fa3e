// SHA-256, streaming, over Debian's nettle (the library libarchive already uses): content
// checksums of datasets' files (db/) and of the files inside course packages (package/), so that a
// moved, damaged or altered file is noticed. Target at_core_sha256 (built with the app only).
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

struct sha256_ctx;  // nettle/sha2.h

namespace at {

class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;

  void update(const unsigned char* data, std::size_t n);
  void update(std::string_view bytes) { update(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size()); }
  // The digest of everything given so far, as 64 lowercase hex digits; the hash starts afresh.
  std::string hex();

 private:
  std::unique_ptr<sha256_ctx> state_;
};

// SHA-256 of a byte string, as 64 lowercase hex digits.
std::string sha256Hex(std::string_view bytes);

}  // namespace at
