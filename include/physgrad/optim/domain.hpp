// Domain — where the unknowns of a direct optimization live: box bounds l ≤ x ≤ u and a
// characteristic scale s of each variable; rules step in z = x ⊘ s (D = diag(s), x = D z).
#pragma once

#include <string>
#include <vector>

#include "physgrad/types.hpp"

namespace physgrad {

// The default Domain is unbounded with unit scale, for any dimension. Setting a scale is the
// same as reformulating the problem in z = x ⊘ s (scipy's x_scale): ∇_z L = D ∇L,
// ∇²_z L = D ∇²L D, ∂P/∂z = J D. Each rule documents what it does with the box
// (docs/update_rules.md): first-order rules project, the others fix the variables held at a
// bound and step in the free ones.
class Domain {
 public:
  Domain() = default;
  // n variables; lower, upper and scale have n entries or none (none: −∞, +∞, 1). Infinite
  // bounds are allowed. Throws Error naming the entry unless every bound is a number (not
  // NaN), lᵢ ≤ uᵢ, lᵢ < +∞, uᵢ > −∞, and every scale is finite and > 0.
  Domain(Index n, Vector lower, Vector upper, Vector scale);

  bool bounded() const { return lower_.size() != 0; }
  bool scaled() const { return scale_.size() != 0; }
  // The bounds and scale as n-vectors (±∞ and 1 where none were given).
  Vector lower(Index n) const;
  Vector upper(Index n) const;
  Vector scale(Index n) const;

  // Throws Error "where: x has k entries, the domain n" when the domain has another dimension.
  void check_dim(Index n, const char* where) const;
  // Throws Error naming the first xᵢ outside [lᵢ, uᵢ] (or NaN), e.g. "x0[2] = -1 is below its
  // lower bound 0"; `name` is the vector's name in the message.
  void check_contains(const Vector& x, const std::string& name) const;

  // Π(x): every xᵢ clamped to [lᵢ, uᵢ].
  Vector project(const Vector& x) const;
  // Π(x + dx) − x: the part of a step that stays in the box.
  Vector feasible_step(const Vector& x, const Vector& dx) const;
  // Whether variable i may move at x along −g: false when xᵢ = lᵢ and gᵢ > 0, or xᵢ = uᵢ and
  // gᵢ < 0 (the gradient pushes it out of the box; it is held at its bound).
  std::vector<bool> free_variables(const Vector& x, const Vector& g) const;
  // The largest α ∈ [0, +∞] with x + α d inside the box (x inside it).
  double max_step(const Vector& x, const Vector& d) const;
  // ‖(x − Π(x − D² g)) ⊘ s‖∞: the projected gradient in z (with no bounds and unit scale ‖g‖∞).
  double projected_gradient_norm(const Vector& x, const Vector& g) const;
  // ‖v ⊘ s‖₂, the length of a step in z.
  double scaled_norm(const Vector& v) const;
  // Variables at one of their bounds.
  Index count_at_bounds(const Vector& x) const;

 private:
  Vector lower_, upper_, scale_;  // empty: none
};

// A step of a second-order rule in the free variables F at x (Domain::free_variables), in scaled
// coordinates z_F: the rule restricts its operators with columns()/square()/covector(), solves
// for Δz_F and maps it back with step(), which leaves the held variables where they are and
// keeps x + Δx in the box.
class FreeSubspace {
 public:
  FreeSubspace(const Domain& domain, const Vector& x, const Vector& g);
  Index size() const { return static_cast<Index>(index_.size()); }
  Vector covector(const Vector& g) const;   // D_F g_F (a gradient in z_F)
  Matrix columns(const Matrix& j) const;    // J[:, F] D_F (a Jacobian in z_F)
  Matrix square(const Matrix& a) const;     // D_F A[F, F] D_F (a curvature in z_F)
  // Δx with Δx_F = D_F Δz_F and 0 elsewhere, cut back to the box by projection.
  Vector step(const Vector& dz) const;

 private:
  Domain domain_;
  Vector x_;
  Vector scale_;
  std::vector<Index> index_;
};

}  // namespace physgrad
