#include "model/selected_inverse.hpp"

#include <algorithm>
#include <stdexcept>

namespace catenary_sim {

SelectedInverse::SelectedInverse(const Ldlt& factor) : l_(factor.matrixL().nestedExpression()) {
  const int n = static_cast<int>(l_.cols());
  // Eigen's simplicial factor: L's strictly lower entries column by column (D apart, the unit
  // diagonal not stored), each column's rows ascending.
  if (!l_.isCompressed()) throw std::logic_error("SelectedInverse: the factor is not compressed");
  const Eigen::VectorXd d = factor.vectorD();
  position_.resize(n);
  if (factor.permutationP().size() == n) position_ = factor.permutationP().indices();
  else
    for (int i = 0; i < n; ++i) position_[i] = i;
  z_.assign(static_cast<std::size_t>(l_.nonZeros()), 0.0);
  diagonal_.assign(n, 0.0);
  const int* outer = l_.outerIndexPtr();
  const int* rows = l_.innerIndexPtr();
  const double* lx = l_.valuePtr();
  for (int j = n - 1; j >= 0; --j) {
    double diag = 1.0 / d[j];
    for (int p = outer[j]; p < outer[j + 1]; ++p) {
      const int i = rows[p];
      double zij = 0.0;
      for (int q = outer[j]; q < outer[j + 1]; ++q) {
        const int k = rows[q];
        zij -= (k == i ? diagonal_[i] : z_[index(std::max(i, k), std::min(i, k))]) * lx[q];
      }
      z_[p] = zij;
    }
    for (int p = outer[j]; p < outer[j + 1]; ++p) diag -= z_[p] * lx[p];
    diagonal_[j] = diag;
  }
}

std::size_t SelectedInverse::index(int row, int col) const {
  const int* begin = l_.innerIndexPtr() + l_.outerIndexPtr()[col];
  const int* end = l_.innerIndexPtr() + l_.outerIndexPtr()[col + 1];
  const int* hit = std::lower_bound(begin, end, row);
  if (hit == end || *hit != row) throw std::logic_error("SelectedInverse: an entry off the factor's pattern");
  return static_cast<std::size_t>(hit - l_.innerIndexPtr());
}

double SelectedInverse::operator()(int a, int b) const {
  const int pa = position_[a], pb = position_[b];
  if (pa == pb) return diagonal_[pa];
  return z_[index(std::max(pa, pb), std::min(pa, pb))];
}

}  // namespace catenary_sim
