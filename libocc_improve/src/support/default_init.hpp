#pragma once
// An allocator whose value-initialisation is default-initialisation: vector::resize leaves trivial
// elements unwritten instead of zeroing them. For scratch arrays that are written before they are read
// and that may be large (a call's measurements: 12 M points are 590 MB, whose zeroing took half a second
// that no stop request could interrupt, and was paid again when the conversion wrote every slot).
#include <memory>
#include <new>
#include <type_traits>
#include <utility>

namespace occ_improve::detail {

template <class T, class Base = std::allocator<T>>
class DefaultInitAllocator : public Base {
public:
  using Base::Base;
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U, typename std::allocator_traits<Base>::template rebind_alloc<U>>;
  };
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    std::allocator_traits<Base>::construct(static_cast<Base&>(*this), p, std::forward<Args>(args)...);
  }
};

}  // namespace occ_improve::detail
