#include "core/name_uuid.h"

#include <nettle/sha1.h>

#include <array>
#include <cstdint>

namespace at {

namespace {

int hexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

std::optional<std::string> uuidV5(std::string_view namespaceUuid, std::string_view name) {
  if (namespaceUuid.size() != 36) return std::nullopt;
  std::array<std::uint8_t, 16> space{};
  std::size_t byte = 0;
  for (std::size_t i = 0; i < namespaceUuid.size();) {
    if (i == 8 || i == 13 || i == 18 || i == 23) {
      if (namespaceUuid[i] != '-') return std::nullopt;
      ++i;
      continue;
    }
    const int high = hexValue(namespaceUuid[i]), low = hexValue(namespaceUuid[i + 1]);
    if (high < 0 || low < 0 || byte >= space.size()) return std::nullopt;
    space[byte++] = std::uint8_t(high * 16 + low);
    i += 2;
  }
  sha1_ctx context;
  sha1_init(&context);
  sha1_update(&context, space.size(), space.data());
  sha1_update(&context, name.size(), reinterpret_cast<const std::uint8_t*>(name.data()));
  std::array<std::uint8_t, SHA1_DIGEST_SIZE> digest{};
  sha1_digest(&context, digest.size(), digest.data());
  digest[6] = std::uint8_t((digest[6] & 0x0F) | 0x50);  // version 5
  digest[8] = std::uint8_t((digest[8] & 0x3F) | 0x80);  // variant 10xx (RFC 4122)
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(36);
  for (std::size_t i = 0; i < 16; ++i) {
    if (i == 4 || i == 6 || i == 8 || i == 10) out += '-';
    out += kHex[digest[i] >> 4];
    out += kHex[digest[i] & 0xF];
  }
  return out;
}

}  // namespace at
