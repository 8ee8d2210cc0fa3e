#include "uuid.h"

#include <cstdint>
#include <random>

namespace at::db {

std::string newUuid() {
  thread_local std::mt19937_64 generator = [] {
    std::random_device device;
    std::seed_seq seed{device(), device(), device(), device(), device(), device(), device(), device()};
    return std::mt19937_64(seed);
  }();
  std::uint64_t high = generator(), low = generator();
  high = (high & ~std::uint64_t(0xF000)) | 0x4000;                       // version 4
  low = (low & ~(std::uint64_t(0xC) << 60)) | (std::uint64_t(0x8) << 60);  // variant 10xx
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(36);
  auto put = [&](std::uint64_t bits, int fromNibble, int count) {
    for (int i = fromNibble; i > fromNibble - count; --i) out += kHex[(bits >> (4 * i)) & 0xF];
  };
  put(high, 15, 8);
  out += '-';
  put(high, 7, 4);
  out += '-';
  put(high, 3, 4);
  out += '-';
  put(low, 15, 4);
  out += '-';
  put(low, 11, 12);
  return out;
}

bool isUuid(const std::string& text) {
  if (text.size() != 36) return false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (i == 8 || i == 13 || i == 18 || i == 23) {
      if (c != '-') return false;
    } else if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) {
      return false;
    }
  }
  return true;
}

}  // namespace at::db
