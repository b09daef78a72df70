// run_machine — what a run was made with: the build's git commit, the CPU model, the BLAS library
// and its kernel set, the thread counts and the date; summary.json's "machine" and each report.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace physgrad::run {

// {"commit", "cpu", "blas", "blas_kernel", "blas_threads", "jacobian_threads", "hardware_threads",
// "date"}: the commit configured into the build ("unknown" when git could not tell), the first
// "model name" of /proc/cpuinfo ("unknown" without one), OpenBLAS's configuration string
// ("unknown" for another BLAS) and kernel set, the thread counts (0: cannot tell) and the UTC
// time now ("2026-11-27 08:40 UTC").
nlohmann::json run_machine();

// The UTC time now to the minute, "2026-11-27 08:40 UTC" (summary.json's date, a page's "Written").
std::string utc_minute_now();

// One line for a page: "commit abc1234 · CPU … · BLAS … (kernel Haswell) · threads: BLAS 1, …".
std::string run_machine_text(const nlohmann::json& machine);

}  // namespace physgrad::run
