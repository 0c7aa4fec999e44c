// The statics' sparse symmetric solve, keeping the fill-reducing ordering of its last pattern.
//
// The design statics solve each wire four times (the droppers' weight fixed point) and the
// initial statics once per active-set guess (eq. 25), each time on the same sparsity pattern.
// The ordering (AMD) is most of a solve's cost; computed once per pattern and reused, the
// factorisation and the solution are the same numbers as a fresh solve's (the ordering depends on
// the pattern alone), so the model is bit for bit the same, only built faster.
#pragma once

#include <Eigen/Core>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <string>
#include <vector>

namespace catenary_sim {

// Eigen's AMD ordering, without its first step. AMDOrdering forms the pattern of A^T + A before
// the minimum degree search, for an A that may not be structurally symmetric; the simplicial
// factorisation hands it the full symmetric matrix (SimplicialCholeskyBase::ordering expands the
// lower triangle first), whose pattern that sum repeats entry for entry. Forming it is most of
// the ordering's time; the search on the matrix itself gives the same permutation.
template <typename StorageIndex>
struct SymmetricAmdOrdering {
  using PermutationType = Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, StorageIndex>;
  template <typename MatrixType>
  void operator()(const MatrixType& full, PermutationType& perm) const {
    Eigen::SparseMatrix<typename MatrixType::Scalar, Eigen::ColMajor, StorageIndex> c = full;  // the search's workspace
    Eigen::internal::minimum_degree_ordering(c, perm);
  }
};

class SpdSolver {
 public:
  // x with k x = r (k symmetric positive definite, lower triangle read). Throws SceneError naming
  // `what` if k is singular or the solution is not finite.
  Eigen::VectorXd solve(const Eigen::SparseMatrix<double>& k, const Eigen::VectorXd& r, const std::string& what);

 private:
  bool same_pattern(const Eigen::SparseMatrix<double>& k) const;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, SymmetricAmdOrdering<int>> ldlt_;
  std::vector<int> outer_, inner_;  // the pattern ldlt_ was analysed for (compressed k)
  bool analysed_ = false;
};

}  // namespace catenary_sim
