// The Newmark average-acceleration matrix of the implicit integrator, factorised once per model.
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "model/assembly.hpp"
#include "model/newmark_matrix.hpp"

namespace catenary_sim {

std::shared_ptr<const ImplicitMatrix> newmark_matrix(const Model& m, double dt) {
  const int n = m.n_dof;
  const double gdt = 0.5 * dt, bdt2 = 0.25 * dt * dt;
  Triplets k, c;
  Eigen::VectorXd unused = Eigen::VectorXd::Zero(n);
  // Catenary stiffness K0: beams, supports and every dropper taut. A dropper that slackens is
  // taken out again in step() by a rank-1 correction (an active set), so the matrix is never
  // refactorised.
  for (const Wire& w : m.wires) add_wire_band(k, w, w.w_dof, w.theta_dof);
  for (const SupportSpring& sp : m.springs) k.emplace_back(sp.dof, sp.dof, sp.stiffness);
  for (const Dropper& d : m.droppers) add_spring(k, unused, d.messenger_dof, d.contact_dof, d.stiffness, 0.0);
  for (const WireClamp& cl : m.clamps) add_spring(k, unused, cl.upper_dof, cl.lower_dof, cl.stiffness, 0.0);
  // Rayleigh damping of the catenary (eq. 5) is beta K0 + alpha M.
  for (const auto& e : k) c.emplace_back(e.row(), e.col(), m.beta * e.value());
  for (int i = 0; i < m.n_catenary_dof; ++i) c.emplace_back(i, i, m.alpha * m.mass[i]);
  // Pantograph chains: springs and dampers (the roof end to ground).
  for (const Pantograph& p : m.pantographs) {
    if (p.moving_force) continue;
    for (int i = 0; i < p.masses_count(); ++i) {
      const int a = p.first_dof + i, b = i + 1 < p.masses_count() ? a + 1 : -1;
      add_spring(k, unused, a, b, p.stiffness[i], 0.0);
      add_spring(c, unused, a, b, p.damping[i], 0.0);
    }
    for (const Head& h : p.heads) {
      add_spring(k, unused, h.dof, p.first_dof, h.stiffness, 0.0);
      add_spring(c, unused, h.dof, p.first_dof, h.damping, 0.0);
    }
  }
  Triplets a;
  for (int i = 0; i < n; ++i) a.emplace_back(i, i, m.mass[i]);
  for (const auto& e : k) a.emplace_back(e.row(), e.col(), bdt2 * e.value());
  for (const auto& e : c) a.emplace_back(e.row(), e.col(), gdt * e.value());
  // Rigid supports: identity rows and columns (their acceleration is 0).
  Triplets ar;
  for (const auto& e : a)
    if (m.inv_mass[e.row()] != 0.0 && m.inv_mass[e.col()] != 0.0) ar.push_back(e);
  for (int i = 0; i < n; ++i)
    if (m.inv_mass[i] == 0.0) ar.emplace_back(i, i, 1.0);
  Eigen::SparseMatrix<double> am(n, n);
  am.setFromTriplets(ar.begin(), ar.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(am);
  if (ldlt.info() != Eigen::Success) throw SceneError("numerics.integrator implicit: the Newmark matrix could not be factorised");

  auto out = std::make_shared<ImplicitMatrix>();
  out->perm.resize(n);
  for (int i = 0; i < n; ++i) out->perm[i] = ldlt.permutationP().indices()[i];
  const Eigen::SparseMatrix<double>& l = ldlt.matrixL().nestedExpression();
  out->col.assign(n + 1, 0);
  for (int j = 0; j < n; ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(l, j); it; ++it)
      if (it.row() > j) {
        out->row.push_back(static_cast<int>(it.row()));
        out->val.push_back(it.value());
      }
    out->col[j + 1] = static_cast<int>(out->row.size());
  }
  out->inv_diag.resize(n);
  for (int i = 0; i < n; ++i) out->inv_diag[i] = 1.0 / ldlt.vectorD()[i];
  // Check the hand-written solve against Eigen's on one right-hand side.
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, 1.0, 2.0), x = ldlt.solve(b), y = b, tmp(n);
  newmark_solve(*out, y.data(), tmp.data());
  if (!((x - y).norm() <= 1e-8 * x.norm()))
    throw SceneError("numerics.integrator implicit: internal check of the factorised solve failed");
  return out;
}

void newmark_solve(const ImplicitMatrix& a, double* b, double* tmp) {
  const int n = static_cast<int>(a.perm.size());
  for (int i = 0; i < n; ++i) tmp[a.perm[i]] = b[i];
  for (int j = 0; j < n; ++j) {
    const double yj = tmp[j];
    for (int p = a.col[j]; p < a.col[j + 1]; ++p) tmp[a.row[p]] -= a.val[p] * yj;
  }
  for (int j = 0; j < n; ++j) tmp[j] *= a.inv_diag[j];
  for (int j = n - 1; j >= 0; --j) {
    double w = tmp[j];
    for (int p = a.col[j]; p < a.col[j + 1]; ++p) w -= a.val[p] * tmp[a.row[p]];
    tmp[j] = w;
  }
  for (int i = 0; i < n; ++i) b[i] = tmp[a.perm[i]];
}

}  // namespace catenary_sim
