// A vector whose copies keep its reserved capacity: a State's bounded logs are reserved once and
// filled in step(), which must never allocate, also in a state copied from another (a copy of a
// plain std::vector gets only the capacity its entries need).
#pragma once

#include <vector>

namespace catenary_sim {

template <class T>
class ReservedVector : public std::vector<T> {
 public:
  ReservedVector() = default;
  ReservedVector(const ReservedVector& other) : std::vector<T>() {
    this->reserve(other.capacity());
    this->assign(other.begin(), other.end());
  }
  ReservedVector(ReservedVector&&) noexcept = default;
  // Assigning grows this vector's room to the other's (allocating only then) and otherwise keeps
  // its storage: restoring a snapshot into a state of the same model allocates nothing.
  ReservedVector& operator=(const ReservedVector& other) {
    if (this != &other) {
      if (this->capacity() < other.capacity()) this->reserve(other.capacity());
      this->assign(other.begin(), other.end());
    }
    return *this;
  }
  ReservedVector& operator=(ReservedVector&&) noexcept = default;
};

}  // namespace catenary_sim
