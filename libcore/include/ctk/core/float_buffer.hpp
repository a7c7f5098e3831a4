#pragma once
// The storage of volumes and projection stacks. Buffers of 2 MB or more are aligned to 2 MB and
// offered to the kernel for transparent huge pages before anything touches them.
// Why: the projectors step from slice to slice of a 256^3 volume 1 kB or 256 kB apart, so with
// 4 kB pages nearly every step of a ray bundle needs a page-table walk (doubly costly in a virtual
// machine); with 2 MB pages a 64 MB volume fits in 32 TLB entries. Linux serves the advice when
// /sys/kernel/mm/transparent_hugepage/enabled says "always" or "madvise"; elsewhere the advice
// is ignored and the buffer behaves like any other.
#include <cstddef>
#include <new>
#include <vector>

namespace ctk {

namespace detail {
inline constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;
void* allocate_large(std::size_t bytes);  // 2 MB aligned, advised, never null
void deallocate_large(void* p);
}  // namespace detail

template <class T>
struct HugePageAllocator {
  using value_type = T;
  static constexpr std::align_val_t kSmallAlignment{alignof(T) > 64 ? alignof(T) : 64};  // a cache line
  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

  T* allocate(std::size_t n) {
    if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_array_new_length();
    const std::size_t bytes = n * sizeof(T);
    if (bytes < detail::kHugePageBytes) return static_cast<T*>(::operator new(bytes, kSmallAlignment));
    return static_cast<T*>(detail::allocate_large(bytes));
  }
  void deallocate(T* p, std::size_t n) noexcept {
    if (n * sizeof(T) < detail::kHugePageBytes)
      ::operator delete(p, kSmallAlignment);
    else
      detail::deallocate_large(p);
  }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const noexcept {
    return true;
  }
};

/// Float storage of volumes and projection stacks (64-byte aligned; huge pages when large).
using FloatBuffer = std::vector<float, HugePageAllocator<float>>;

}  // namespace ctk
