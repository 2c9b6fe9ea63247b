#pragma once
// An allocator whose construct() without arguments default-initializes: resize() on a
// std::vector<T, DefaultInit<T>> leaves trivially constructible elements unwritten. For the
// working arrays that a parallel pass then fills entirely: their pages are first touched by that
// pass, on its threads, instead of being zeroed first by the one thread that resizes.
#include <cstddef>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace particle::detail {

template <class T, class Base = std::allocator<T>>
class DefaultInit : public Base {
  using Traits = std::allocator_traits<Base>;

 public:
  template <class U>
  struct rebind {
    using other = DefaultInit<U, typename Traits::template rebind_alloc<U>>;
  };
  using Base::Base;

  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    Traits::construct(static_cast<Base&>(*this), p, std::forward<Args>(args)...);
  }
};

// A vector whose resize() does not write the new elements (DefaultInit).
template <class T>
using Uninitialized = std::vector<T, DefaultInit<T>>;

// An allocator of arrays that start on a cache line: a 64-byte load at a multiple of 64 bytes from
// the start then touches one line, not two (FloatGroups' 16-float groups).
template <class T>
struct LineAllocator {
  using value_type = T;
  static constexpr std::align_val_t kLine{64};

  LineAllocator() = default;
  template <class U>
  LineAllocator(const LineAllocator<U>&) noexcept {}

  T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), kLine)); }
  void deallocate(T* p, std::size_t) noexcept { ::operator delete(p, kLine); }

  template <class U>
  bool operator==(const LineAllocator<U>&) const noexcept {
    return true;
  }
};

// An Uninitialized vector whose data() starts on a cache line.
template <class T>
using LineAligned = std::vector<T, DefaultInit<T, LineAllocator<T>>>;

}  // namespace particle::detail
