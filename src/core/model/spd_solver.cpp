#include "model/spd_solver.hpp"

#include <algorithm>

#include "catenary_sim/core/scene/scene.hpp"

namespace catenary_sim {

bool SpdSolver::same_pattern(const Eigen::SparseMatrix<double>& k) const {
  const int n = static_cast<int>(k.outerSize());
  return analysed_ && static_cast<int>(outer_.size()) == n + 1 &&
         std::equal(outer_.begin(), outer_.end(), k.outerIndexPtr()) &&
         static_cast<Eigen::Index>(inner_.size()) == k.nonZeros() &&
         std::equal(inner_.begin(), inner_.end(), k.innerIndexPtr());
}

Eigen::VectorXd SpdSolver::solve(const Eigen::SparseMatrix<double>& k, const Eigen::VectorXd& r, const std::string& what) {
  // setFromTriplets leaves k compressed, so its pattern is outer and inner indices alone.
  if (!same_pattern(k)) {
    ldlt_.analyzePattern(k);
    outer_.assign(k.outerIndexPtr(), k.outerIndexPtr() + k.outerSize() + 1);
    inner_.assign(k.innerIndexPtr(), k.innerIndexPtr() + k.nonZeros());
    analysed_ = true;
  }
  ldlt_.factorize(k);
  // Beside a part held by nothing, a stiffness next to nothing against the rest (a contact spring
  // or a dropper's EA of 1e-308, within their open ranges) leaves the solve nothing to hold.
  const char* check = "; check the scene's smallest stiffnesses and tensions (contact.stiffness, "
                      "droppers.axial_stiffness, the wires' tension) against the rest";
  if (ldlt_.info() != Eigen::Success)
    throw SceneError("statics: " + what + " is singular (a part of the system is not held by any support)" + check);
  Eigen::VectorXd x = ldlt_.solve(r);
  if (!x.allFinite()) throw SceneError("statics: " + what + " has no finite solution" + check);
  return x;
}

}  // namespace catenary_sim
