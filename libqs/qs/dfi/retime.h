#pragma once
// Even frame times for a DFI morph: frames placed so that consecutive frames change about equally.
//
// The blend moves its surface unevenly in t: slowly where both fields agree, fast where a handle
// opens or a part pinches off (the surface's speed is the field's change over its gradient, which
// vanishes at such events). even_frame_times samples the morph densely on a coarser copy of its
// grid (cheap frames), measures the change between consecutive dense frames (the two-sided largest
// distance from the vertices of one to the surface of the other), bisects the dense steps that
// change more than an output step should, and places the output frames at equal steps of the
// cumulative change. Deterministic: the same morph and options give the same times on any number
// of threads.

#include <vector>

#include "qs/dfi/pipeline.h"

namespace qs::dfi {

struct RetimeOptions {
  int samples_per_frame = 4;  ///< dense frames per output step before refinement (>= 1)
  int coarsen = 2;            ///< the dense frames sample every coarsen-th grid sample (>= 1)
  int refine_passes = 3;      ///< bisection passes over dense steps that change more than half an output step
  /// Share of the parameterization that stays uniform in t (0..1): the cumulative change is
  /// (1 - share) * change / total + share * t, strictly increasing even where nothing changes.
  double uniform_share = 0.05;
};

struct Retiming {
  std::vector<double> times;         ///< one per output frame: times[0] = 0, times.back() = 1, increasing
  std::vector<double> dense_times;   ///< the dense samples, increasing, from 0 to 1
  std::vector<double> dense_change;  ///< change between dense sample i and i + 1 (world units, morph space)
};

/// Frame times for `frames` (>= 2) frames. \throws InvalidInput for options out of range.
Retiming even_frame_times(const PreparedMorph& morph, int frames, const RetimeOptions& options = {}, int threads = 0);

/// Times at equal steps of the cumulative change: `change[i]` between dense samples `dense[i]` and
/// `dense[i + 1]` (dense increasing from 0 to 1), mixed with `uniform_share` of t. Monotone,
/// times[0] = 0 and times.back() = 1 exactly.
std::vector<double> equalize_times(const std::vector<double>& dense, const std::vector<double>& change, int frames,
                                   double uniform_share);

}  // namespace qs::dfi
