// An owner of one T that copies it deep, for a T whose definition stays private to its stage (the
// engine's step workspaces, engine/*_workspace.hpp): the public headers see only its declaration,
// so skins cannot reach into it, and yet a copied State carries its own T and steps as the
// original would. The members are defined in util/deep_copied_impl.hpp (src/core) and
// instantiated beside T's definition (template class DeepCopied<T>;).
#pragma once

#include <memory>

namespace catenary_sim {

template <class T>
class DeepCopied {
 public:
  DeepCopied();
  DeepCopied(const DeepCopied& other);
  DeepCopied(DeepCopied&& other) noexcept;
  DeepCopied& operator=(const DeepCopied& other);
  DeepCopied& operator=(DeepCopied&& other) noexcept;
  ~DeepCopied();
  T& operator*() { return *owned_; }
  const T& operator*() const { return *owned_; }
  T* operator->() { return owned_.get(); }
  const T* operator->() const { return owned_.get(); }

 private:
  std::unique_ptr<T> owned_;
};

}  // namespace catenary_sim
