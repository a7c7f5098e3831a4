#include "ctk/core/float_buffer.hpp"

#include <cstdlib>
#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace ctk::detail {

namespace {
std::size_t whole_huge_pages(std::size_t bytes) { return (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes; }
}  // namespace

void* allocate_large(std::size_t bytes) {
  const std::size_t rounded = whole_huge_pages(bytes);
  void* p = std::aligned_alloc(kHugePageBytes, rounded);
  if (p == nullptr) throw std::bad_alloc();
#if defined(MADV_HUGEPAGE)
  // Advice only: a kernel without transparent huge pages refuses it and 4 kB pages serve.
  (void)madvise(p, rounded, MADV_HUGEPAGE);
#endif
  return p;
}

void deallocate_large(void* p) { std::free(p); }

}  // namespace ctk::detail
