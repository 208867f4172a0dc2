// PageVector: a std::vector whose large buffers are mapped from the kernel directly, so that a
// buffer given up when the vector grows goes back to the system at once.
//
// Why: the contact lists and history carries grow step by step while a bed compacts, each
// growth freeing the previous buffer. glibc's malloc raises its mmap threshold to the size of
// every mapped block freed (up to 32 MiB; "M_MMAP_THRESHOLD", mallopt(3)), so after the first
// few such frees these buffers come from the heap, whose freed holes stay resident: in the
// dense 50k bed of bench/python/dense_bed.py that kept 5-11 MiB of freed lists in the peak
// RSS. Small buffers take the ordinary allocator; fresh mappings read as zero.
#pragma once

#include <cstddef>
#include <new>
#include <vector>

#if defined(__unix__) || defined(__APPLE__)
#include <sys/mman.h>
#define GRAINSCALE_HAVE_MMAP 1
#endif

namespace grainscale {

template <class T>
struct PageAllocator {
  using value_type = T;
  // Blocks from this size up are mapped (glibc's initial mmap threshold).
  static constexpr std::size_t kMapBytes = std::size_t(128) << 10;

  PageAllocator() = default;
  template <class U>
  PageAllocator(const PageAllocator<U>&) noexcept {}  // NOLINT: rebinding, as std::allocator

  T* allocate(std::size_t n) {
    const std::size_t bytes = n * sizeof(T);
#if GRAINSCALE_HAVE_MMAP
    if (bytes >= kMapBytes) {
      void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
      if (p == MAP_FAILED) throw std::bad_alloc();
      return static_cast<T*>(p);
    }
#endif
    return static_cast<T*>(::operator new(bytes));
  }
  void deallocate(T* p, std::size_t n) noexcept {
#if GRAINSCALE_HAVE_MMAP
    if (n * sizeof(T) >= kMapBytes) {
      munmap(p, n * sizeof(T));
      return;
    }
#endif
    ::operator delete(p);
  }
  template <class U>
  bool operator==(const PageAllocator<U>&) const noexcept {
    return true;
  }
  template <class U>
  bool operator!=(const PageAllocator<U>&) const noexcept {
    return false;
  }
};

template <class T>
using PageVector = std::vector<T, PageAllocator<T>>;

// Room for n elements and some to grow. resize() and assign() of a cleared vector map exactly
// n, so a contact list that gains a few entries at every rebuild (a compacting bed) was mapped
// afresh each time, its pages faulted in and cleared by the kernel again: about 1000 page faults
// per rebuild in the dense 50k bed. The headroom's pages are not resident until written.
// reserve_growing drops the contents when it has to grow.
template <class T>
void reserve_growing(PageVector<T>& v, std::size_t n) {
  if (n > v.capacity()) {
    PageVector<T>().swap(v);  // the old buffer goes first: never two at once
    v.reserve(n + n / 8);
  }
}
// v = n copies of value, with room to grow.
template <class T>
void assign_growing(PageVector<T>& v, std::size_t n, const T& value) {
  reserve_growing(v, n);
  v.assign(n, value);
}

}  // namespace grainscale
