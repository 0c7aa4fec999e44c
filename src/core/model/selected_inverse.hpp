// Entries of a sparse symmetric matrix's inverse without forming it: those on the pattern of its
// LDL^T factor (the selected inverse; Takahashi, Fagan and Chin 1973, Erisman and Tinney 1975).
//
// With A = P^T L D L^T P, Z = (L D L^T)^-1 satisfies Z L = L^-T D^-1, upper triangular with
// diagonal D^-1, so column by column from the last:
//   Z_ij = -sum_{k in P_j} Z_ik L_kj  (i in P_j),   Z_jj = 1/D_j - sum_{k in P_j} Z_jk L_kj,
// P_j the rows of L's column j below the diagonal. Every Z_ik these need (i, k in P_j) lies on
// L's pattern (a column's rows are a clique of the filled graph), so the sweep costs
// sum_j |P_j|^2 (log of a column's length to find an entry) where a solve per wanted column
// costs the whole factor: on a line of spans, O(n) against O(n^2) for n columns.
//
// An entry (a, b) is on the pattern when A stores it (an explicit zero will do: the symbolic
// factorisation keeps stored zeros), or fill put it there.
#pragma once

#include <Eigen/Core>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <vector>

namespace catenary_sim {

class SelectedInverse {
 public:
  using Ldlt = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>;
  explicit SelectedInverse(const Ldlt& factor);
  // (A^-1)_ab in A's numbering; throws std::logic_error where (a, b) is off the factor's pattern.
  double operator()(int a, int b) const;

 private:
  std::size_t index(int row, int col) const;  // z_'s entry (factor's numbering, row > col)
  const Eigen::SparseMatrix<double>& l_;       // the factor's L: this lives no longer than it
  std::vector<double> z_, diagonal_;  // z_ parallel to l_'s stored entries
  Eigen::VectorXi position_;          // A's index -> the factor's
};

}  // namespace catenary_sim
