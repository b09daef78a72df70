// ConvNetwork's 64×64 U-net (phiml's u_net(1, 1) shape): forward + backward of Σ gy ⊙ f(x) at
// batch 128, without and with batch norm, on --threads=K conv threads (one BLAS thread each).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstring>
#include <string>

#include "physgrad/nn/conv_net.hpp"
#include "physgrad/threads.hpp"

namespace physgrad {
namespace {

void BM_UNetForwardBackward(benchmark::State& state) {
  UNetOptions options;
  options.batch_norm = state.range(0) != 0;
  ConvNetwork net = ConvNetwork::unet(options);
  net.initialize(1);
  const Index batch = 128;
  const Matrix x = (Matrix::Random(net.input_dim(), batch).array() + 1.0) / 2.0;
  const Matrix gy = (Matrix::Random(net.output_dim(), batch).array() + 1.0) / 2.0;
  auto cache = net.new_cache();
  for (auto _ : state) {
    net.forward(x, *cache);
    benchmark::DoNotOptimize(net.backward(*cache, gy));
  }
}
BENCHMARK(BM_UNetForwardBackward)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace physgrad

int main(int argc, char** argv) {
  int threads = 1;
  for (int k = 1; k < argc; ++k) {
    if (std::strncmp(argv[k], "--threads=", 10) == 0) threads = std::atoi(argv[k] + 10);
  }
  physgrad::set_blas_threads(1);  // the samples are split over the threads instead
  physgrad::set_conv_threads(threads);
  benchmark::AddCustomContext("threads", std::to_string(threads));
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
