// DeepCopied's members (catenary_sim/core/util/deep_copied.hpp), for the file that defines T and
// instantiates DeepCopied<T> once for the whole library.
#pragma once

#include <memory>

#include "catenary_sim/core/util/deep_copied.hpp"

namespace catenary_sim {

template <class T>
DeepCopied<T>::DeepCopied() : owned_(std::make_unique<T>()) {}
template <class T>
DeepCopied<T>::DeepCopied(const DeepCopied& other) : owned_(other.owned_ ? std::make_unique<T>(*other.owned_) : nullptr) {}
template <class T>
DeepCopied<T>::DeepCopied(DeepCopied&& other) noexcept = default;
// Into an existing T: its buffers keep their storage when the sizes match (a skin restoring a
// snapshot of the same model allocates nothing).
template <class T>
DeepCopied<T>& DeepCopied<T>::operator=(const DeepCopied& other) {
  if (this == &other) return *this;
  if (!other.owned_) owned_.reset();
  else if (owned_) *owned_ = *other.owned_;
  else owned_ = std::make_unique<T>(*other.owned_);
  return *this;
}
template <class T>
DeepCopied<T>& DeepCopied<T>::operator=(DeepCopied&& other) noexcept = default;
template <class T>
DeepCopied<T>::~DeepCopied() = default;

}  // namespace catenary_sim
