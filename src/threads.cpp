#include "physgrad/threads.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <string>

#include "physgrad/error.hpp"

namespace physgrad {

// Looked up at run time so the library links against any BLAS, not only OpenBLAS.
bool set_blas_threads(int threads) {
  if (threads < 1) throw Error("threads must be ≥ 1, got " + std::to_string(threads));
  using Setter = void (*)(int);
  const auto setter = reinterpret_cast<Setter>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
  if (setter == nullptr) return false;
  setter(threads);
  return true;
}

int blas_threads() {
  using Getter = int (*)();
  const auto getter = reinterpret_cast<Getter>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  return getter == nullptr ? 0 : getter();
}

std::string blas_core() {
  using Getter = char* (*)();
  const auto getter = reinterpret_cast<Getter>(dlsym(RTLD_DEFAULT, "openblas_get_corename"));
  const char* name = getter == nullptr ? nullptr : getter();
  return name == nullptr ? "" : name;
}

std::string blas_core_note() {
#if defined(__x86_64__) && defined(__GNUC__)
  const std::string core = blas_core();
  std::string lower = core;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  // OpenBLAS's x86-64 kernel sets that use neither AVX2 nor FMA.
  static const std::array<const char*, 7> kGeneric = {
      "prescott", "core2", "penryn", "dunnington", "nehalem", "atom", "sandybridge"};
  const bool generic = std::find(kGeneric.begin(), kGeneric.end(), lower) != kGeneric.end();
  if (!generic || !__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) return "";
  const bool avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
                      __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512dq");
  return "note: OpenBLAS runs its generic " + core +
         " kernels on this CPU, which has AVX2" + (avx512 ? " and AVX-512" : "") +
         "; OPENBLAS_CORETYPE=" + (avx512 ? "SkylakeX" : "Haswell") +
         " in the environment makes the linear algebra several times faster";
#else
  return "";
#endif
}

namespace {
std::atomic<int> jacobian_thread_count{1};
}  // namespace

void set_jacobian_threads(int threads) {
  if (threads < 1) throw Error("threads must be ≥ 1, got " + std::to_string(threads));
  jacobian_thread_count.store(threads);
}

int jacobian_threads() { return jacobian_thread_count.load(); }

}  // namespace physgrad
