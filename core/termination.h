#pragma once
// How an iterative solver ended: one vocabulary for every solver of photopose (the pose
// refinement, the resection, the Taylor resection and bundle, the bundle adjustment), printed
// "converged", "no_convergence", "failure", "cancelled" in reports and JSON.

#include "core/enum_names.h"

namespace photopose {

enum class SolverTermination {
  kConverged,      // the convergence test was met: the solution is usable
  kNoConvergence,  // the iteration limit came first; no solution
  kFailure,        // invalid input, degenerate geometry, a point behind a camera, divergence,
                   // a singular or non-finite problem; no solution
  kCancelled,      // the caller's progress hook asked to stop; no solution, and no verdict on
                   // the data (not a failure)
};

inline constexpr EnumNameEntry<SolverTermination> kSolverTerminationNames[] = {
    {SolverTermination::kConverged, "converged"},
    {SolverTermination::kNoConvergence, "no_convergence"},
    {SolverTermination::kFailure, "failure"},
    {SolverTermination::kCancelled, "cancelled"}};
constexpr EnumNameTable<SolverTermination> EnumNames(SolverTermination) {
  return EnumNameTable<SolverTermination>(kSolverTerminationNames);
}

}  // namespace photopose
