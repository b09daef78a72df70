// The main() of a micro-benchmark program: one BLAS thread (the step costs the docs quote), the
// OpenBLAS kernel in the output's context and a note on stderr where it is a slow generic one.
#pragma once

#include <benchmark/benchmark.h>

#include <cstdio>
#include <string>

#include "physgrad/threads.hpp"

namespace physgrad::bench {

inline int run_single_thread_benchmarks(int argc, char** argv) {
  set_blas_threads(1);
  benchmark::AddCustomContext("blas_core", blas_core());
  if (const std::string note = blas_core_note(); !note.empty()) {
    std::fprintf(stderr, "%s\n", note.c_str());
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

}  // namespace physgrad::bench
