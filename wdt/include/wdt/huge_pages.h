// Large arrays that are about to be filled, backed by transparent huge pages where the kernel
// offers them on request (THP "madvise" mode): the WDT backends' fields and scratch. A 256³ run
// touches ~180 MB of fresh memory; with 4 KiB pages the page faults alone cost more CPU time than
// a sweep pass. Elsewhere than Linux the advice is a no-op.
#pragma once

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include <cstddef>
#include <cstdint>
#include <vector>

namespace at::wdt {

// Asks for huge pages on the 2 MiB-aligned part of [p, p + bytes). Advisory: ignored if unsupported.
inline void adviseHugePages([[maybe_unused]] void* p, [[maybe_unused]] std::size_t bytes) {
#if defined(__linux__)
  constexpr std::uintptr_t kHuge = std::uintptr_t(2) << 20;
  const std::uintptr_t begin = (reinterpret_cast<std::uintptr_t>(p) + kHuge - 1) & ~(kHuge - 1);
  const std::uintptr_t end = (reinterpret_cast<std::uintptr_t>(p) + bytes) & ~(kHuge - 1);
  if (end > begin) (void)madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#endif
}

// Resizes an empty vector to n elements, asking for huge pages before the first touch.
template <class T>
void resizeOnHugePages(std::vector<T>& v, std::size_t n) {
  v.reserve(n);
  adviseHugePages(v.data(), n * sizeof(T));
  v.resize(n);
}

// An uninitialised array on huge pages (scratch that the caller fills first).
template <class T>
T* newOnHugePages(std::size_t n) {
  T* p = new T[n];
  adviseHugePages(p, n * sizeof(T));
  return p;
}

}  // namespace at::wdt
