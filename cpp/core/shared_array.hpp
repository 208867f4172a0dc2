// A growable array whose buffer is reference counted, so that zero-copy numpy views handed to
// Python can never dangle: a view keeps the buffer it was made from alive even after the store
// has grown into a new one (it then sees stale data, never freed memory).
#pragma once

#include <algorithm>
#include <cstddef>
#include <memory>

namespace grainscale {

template <class T>
class SharedArray {
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
    std::shared_ptr<T[]> grown(new T[cap]);
    std::copy(buffer_.get(), buffer_.get() + size_, grown.get());
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
