// The tables of docs/performance.md — one Markdown table per question, read from the benchmark
// results: step times per reference case, their ratios, the backends, the eigen and Lanczos
// routes.
#pragma once

#include <string>

#include "bench_results.hpp"

namespace physgrad::bench {

// J's shape, forming J Jᵀ, the whole step of each rule, HIG's backend and the dsyevd of its size,
// one column per reference case.
std::string reference_table(const Results& r);
// The ratios the text discusses (HIG step against dsyevd, factored against formed J Jᵀ, threads),
// one bullet each.
std::string ratios(const Results& r);
// The pseudo-inverse backends on a random J and dsyevd alone by size, one paragraph.
std::string backends(const Results& r);
// f(G)·g on the reference Gram matrices by eigensolve mode.
std::string eigen_route_table(const Results& r);
// f(G)·g from k Lanczos steps against the dsyevd result.
std::string lanczos_table(const Results& r);

}  // namespace physgrad::bench
