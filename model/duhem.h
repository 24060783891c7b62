// A Duhem-type hysteresis model of a piezo actuator (issue 14): the Coleman–Hodgdon /
// backlash-like law generalised with a cubic anhysteretic curve and a rate-dependent relaxation,
//
//   dy/dt = α |du/dt| (f(u) − y) + b du/dt + λ (f(u) − y),     f(u) = c u + c₃ u³,
//
// α [1/V] the rate-independent return towards the anhysteretic curve f, b [y/V] the slope right
// after a reversal, λ [1/s] a first-order relaxation towards f (creep-like; λ = 0 gives a
// rate-independent model, and with c₃ = 0 the backlash-like model of model/stack_models.h).
// Sparse identification of the 150 V real-piezo record found a model of this shape (README of that
// data: dy/dt = −0.176 − 2.388 y + 0.581 V + 0.119 dV/dt − 0.076 y|y|).
//
// Discretisation (stated; tests/model/duhem_test.cc checks it against a fine RK4 reference): the
// drive is the straight line between samples, so du/dt = s is constant on each interval and the
// state w = f(u) − y obeys the linear ODE dw/dt = −k w + g(t), k = α|s| + λ ≥ 0, whose forcing
// g = s (f'(u) − b) is a quadratic in t there. The interval is integrated in closed form (the
// exponential integrator with φ1, φ2, φ3): EXACT for the piecewise-linear drive, for any k (no
// step limit), like the backlash-like model. Initial state: at rest on the curve, y_0 = f(u_0).
// Pure, allocation-free, thread-safe.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "model/status.h"

namespace pz::model {

struct DuhemParams {
  double alpha = 0.02;      ///< [1/V], ≥ 0
  double c = 0.1;           ///< [y/V]
  double c3 = 0;            ///< [y/V³]
  double b = 0.05;          ///< [y/V]
  double lambda = 0;        ///< [1/s], ≥ 0
  Status Validate() const;  ///< finite, α ≥ 0, λ ≥ 0; names the field
};

/// {alpha, c, c3, b, lambda}.
const std::vector<std::string>& DuhemParamNames();
DuhemParams DuhemFromVector(std::span<const double> p);  ///< throws InputError on a wrong size

/// Simulates from rest on u (step dt > 0) into y (same length). Throws InputError on invalid
/// parameters, dt or lengths.
void SimulateDuhem(const DuhemParams& p, std::span<const double> u, double dt, std::span<double> y);

}  // namespace pz::model
