// The fin modes' exact discretisation (spec "bimorph-fin model" §6) is the step kernel's
// (model/kernels/fin_modal.h pzk_fin_make_poles, pzk_fin_discretise: its comment has the
// mathematics). Here: its types for the C++ side, and DiscretiseBatch, both paths'
// discretisation of every mode over a step cut at a breakpoint (docs/architecture.md "The fin's
// step": a second path, kept for its figure and for the HGANN digests made with it).
#pragma once

#include "model/kernels/pzk.h"

namespace pz::model::modal {

/// Highest φ index of a mode's step: D_0 … D_kMaxPhi (a quintic hold needs φ_1 … φ_6, D_0 … D_6).
inline constexpr int kMaxPhi = 6;
/// A mode's poles (roots of λ² + c λ + ω² = 0) and its step over τ: E = e^{τA}, the D_j.
using ModePoles = pzk::pzk_fin_poles;
using ModeStep = pzk::pzk_fin_step_t;

/// pzk_fin_discretise for the n modes poles[0 … n) over one step τ, into out[0 … n): the same
/// values to a few ulps. The modes with real, well separated roots (every mode once δ ω² ≫ ω, the
/// usual case) go through one branch-free loop over the modes (vectorised, e^x by ExpReduced); the
/// others through pzk_fin_discretise. `scratch` holds 16 n doubles, `idx` n ints.
void DiscretiseBatch(int n, const ModePoles* poles, double tau, ModeStep* out, double* scratch,
                     int* idx);

}  // namespace pz::model::modal
