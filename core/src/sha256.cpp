// SHA-256 through nettle (nettle/sha2.h): the hashing itself is the library's.
#include "core/sha256.h"

#include <nettle/sha2.h>

namespace at {

Sha256::Sha256() : state_(std::make_unique<sha256_ctx>()) { sha256_init(state_.get()); }

Sha256::~Sha256() = default;

void Sha256::update(const unsigned char* data, std::size_t n) {
  // nettle takes a size_t; large buffers are fine.
  if (n > 0) sha256_update(state_.get(), n, data);
}

std::string Sha256::hex() {
  unsigned char digest[SHA256_DIGEST_SIZE];
  sha256_digest(state_.get(), SHA256_DIGEST_SIZE, digest);  // also re-initialises the state
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out;
  out.reserve(2 * SHA256_DIGEST_SIZE);
  for (unsigned char byte : digest) {
    out.push_back(kDigits[byte >> 4]);
    out.push_back(kDigits[byte & 0xf]);
  }
  return out;
}

std::string sha256Hex(std::string_view bytes) {
  Sha256 sha;
  sha.update(bytes);
  return sha.hex();
}

}  // namespace at
