// The benchmarks' arm: the Panda with Gaz et al. 2019's inertia and the Franka Hand (csp_bench,
// csp_batch_bench, csp_pinocchio_bench), and its states (bench_states.hpp). CSP's side only.
#pragma once

#include "bench_states.hpp"
#include "csp/dynamics/model.hpp"

namespace csp::bench {

const Model& model();

}  // namespace csp::bench
