// A growable array whose buffer is reference counted, so that zero-copy numpy views handed to
// Python can never dangle: a view keeps the buffer it was made from alive even after the store
// has grown into a new one (it then sees stale data, never freed memory).
//
// Buffers of 2 MiB and more are 2 MiB aligned and advised as transparent huge pages: the force
// loop reads partners' positions and velocities scattered over several such arrays, and with
// 4 KiB pages a large system misses the TLB on most of those reads (200k-particle settle case:
// 6 % faster per step).
//
// Buffers of 4 KiB and more start at staggered offsets from their block's alignment (a
// multiple of 64 bytes, different for consecutive buffers). Arrays that all start at the same
// address modulo 4 KiB put f[j] and t[j], or x[i] and v[i], at the same 12 low address bits,
// and the core then takes a load for one as depending on a pending store to the other ("4K
// aliasing"), and waits. With 2 MiB-aligned arrays, the pair loop's replay waited on every
// t[j] -= ... after f[j] -= ...: the dense 200k bed ran 68.6 -> 53.5 ns per particle-step
// staggered (bench/README.md).
#pragma once

#include <algorithm>
#include <atomic>
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

// Raw storage for `count` objects of `bytes_each` bytes: `data`, inside the block `base` that
// std::free releases.
struct Buffer {
  void* base;
  void* data;
};

// The offset of the next buffer of 4 KiB or more: steps of 17 x 64 bytes modulo 4 KiB, so that
// 64 consecutive buffers all start at different addresses modulo 4 KiB, and neighbours 1 KiB
// or more apart (a loop that streams two arrays runs far less than that ahead).
inline std::size_t next_stagger() {
  static std::atomic<unsigned> count{0};
  return (count.fetch_add(1, std::memory_order_relaxed) % 64 * 17 % 64 + 1) * 64 % 4096;
}

inline Buffer allocate_buffer(std::size_t count, std::size_t bytes_each, std::size_t align) {
  const std::size_t bytes = std::max<std::size_t>(count * bytes_each, 1);
  constexpr std::size_t kPage = 4096;
  const bool staggered = bytes >= kPage && align <= 64;
  const std::size_t offset = staggered ? next_stagger() : 0;
  // The block's alignment: a huge page, a page (so that the offset is the data's address
  // modulo 4 KiB), or what the type needs.
  const std::size_t a = bytes >= kHugePage ? kHugePage
                        : staggered        ? kPage
                                           : std::max(align, alignof(std::max_align_t));
  const std::size_t rounded = (offset + bytes + a - 1) / a * a;
  void* p = std::aligned_alloc(a, rounded);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (p && a == kHugePage) madvise(p, rounded, MADV_HUGEPAGE);  // advice only (THP may be off)
#endif
  if (!p) throw std::bad_alloc();
  return {p, static_cast<char*>(p) + offset};
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
    const detail::Buffer block = detail::allocate_buffer(cap, sizeof(T), alignof(T));
    T* raw = static_cast<T*>(block.data);
    std::shared_ptr<T[]> grown(raw, [base = block.base](T*) { std::free(base); });
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
