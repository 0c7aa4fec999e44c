// The selected inverse (Takahashi's sweep over an LDL^T factor) against the dense inverse.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <stdexcept>
#include <vector>

#include "model/selected_inverse.hpp"

namespace catenary_sim {
namespace {

// A line of strings' kind of matrix: a chain (each node tied to the next) with ties that skip
// along it (as a stitch wire bridges a support), diagonally dominant so positive definite, and
// a few rows held as the identity. `wanted` pairs go on the pattern as stored zeros.
Eigen::SparseMatrix<double> chain_with_skips(int n, const std::vector<std::pair<int, int>>& wanted) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> tie(0.5, 2.0);
  std::vector<Eigen::Triplet<double>> t;
  std::vector<double> diagonal(n, 0.1);
  auto link = [&](int a, int b) {
    const double k = tie(rng);
    t.emplace_back(std::max(a, b), std::min(a, b), -k);
    diagonal[a] += k;
    diagonal[b] += k;
  };
  for (int i = 0; i + 1 < n; ++i)
    if (i % 10 != 9) link(i, i + 1);  // every tenth node held: the chain breaks there
  for (int i = 5; i + 10 < n; i += 10) link(i, i + 10);  // skips over the held nodes
  for (int i = 0; i < n; ++i) t.emplace_back(i, i, i % 10 == 9 ? 1.0 : diagonal[i]);
  for (const auto& [a, b] : wanted) t.emplace_back(std::max(a, b), std::min(a, b), 0.0);
  Eigen::SparseMatrix<double> a(n, n);
  a.setFromTriplets(t.begin(), t.end());
  return a;
}

TEST(SelectedInverse, EqualsTheDenseInverseOnTheFactorsPattern) {
  const int n = 60;
  // Pairs a solve would reach only through the held rows' chain breaks and the skips.
  const std::vector<std::pair<int, int>> wanted = {{8, 10}, {3, 27}, {41, 12}, {0, 58}};
  const Eigen::SparseMatrix<double> a = chain_with_skips(n, wanted);
  const SelectedInverse::Ldlt ldlt(a);
  ASSERT_EQ(ldlt.info(), Eigen::Success);
  const SelectedInverse z(ldlt);
  Eigen::MatrixXd symmetric = Eigen::MatrixXd(a);
  symmetric = symmetric.selfadjointView<Eigen::Lower>();
  const Eigen::MatrixXd dense = symmetric.inverse();
  // Both are backward stable solves of a matrix of condition number below 1e3 (diagonal margin
  // 0.1 on ties of 0.5-2 over chains of nine): agreement to 1e-12 of the largest entry leaves
  // room for their rounding while a wrong term in the sweep (a dropped L_kj) is of order one.
  const double tolerance = 1e-12 * dense.cwiseAbs().maxCoeff();
  int checked = 0;
  for (int j = 0; j < n; ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, j); it; ++it) {
      EXPECT_NEAR(z(static_cast<int>(it.row()), j), dense(it.row(), j), tolerance) << it.row() << ", " << j;
      EXPECT_NEAR(z(j, static_cast<int>(it.row())), dense(it.row(), j), tolerance) << j << ", " << it.row();
      ++checked;
    }
  for (const auto& [p, q] : wanted) {
    EXPECT_NE(dense(p, q), 0.0) << "the pair is coupled through the rest";
    EXPECT_NEAR(z(p, q), dense(p, q), tolerance) << p << ", " << q;
  }
  EXPECT_GT(checked, 2 * n);
}

TEST(SelectedInverse, RefusesAnEntryOffThePattern) {
  const Eigen::SparseMatrix<double> a = chain_with_skips(30, {});
  const SelectedInverse::Ldlt ldlt(a);
  const SelectedInverse z(ldlt);
  // The factor of chains is far from dense: some entry of row 0 is off its pattern, and asking
  // for it throws rather than answering 0.
  bool refused = false;
  for (int b = 2; b < 30 && !refused; ++b) try {
      z(0, b);
    } catch (const std::logic_error&) {
      refused = true;
    }
  EXPECT_TRUE(refused);
}

}  // namespace
}  // namespace catenary_sim
