#include "physgrad/threads.hpp"

#include <dlfcn.h>

#include <atomic>
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

namespace {
std::atomic<int> jacobian_thread_count{1};
}  // namespace

void set_jacobian_threads(int threads) {
  if (threads < 1) throw Error("threads must be ≥ 1, got " + std::to_string(threads));
  jacobian_thread_count.store(threads);
}

int jacobian_threads() { return jacobian_thread_count.load(); }

}  // namespace physgrad
