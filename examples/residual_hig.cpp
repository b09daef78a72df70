// A network of one's own trained with HIG: the ResidualNetwork of residual_network.hpp (a
// physgrad::Network) steers the pendulum of pendulum.hpp; its derivatives checked first.
#include <cmath>
#include <cstdio>

#include "pendulum.hpp"
#include "physgrad/physgrad.hpp"
#include "residual_network.hpp"

namespace {

using example::Index;
using example::Matrix;
using example::Vector;

// Largest deviation of the network's per-sample gradient rows, ∇θ and Gram matrix from
// independent references: central differences of forward(), the sum of the rows, and the
// Network default that forms the rows.
double derivative_error(const example::ResidualNetwork& network) {
  const Matrix x = Matrix::Random(network.input_dim(), 3);
  const auto cache = network.new_cache();
  network.forward(x, *cache);
  double error = 0;
  std::vector<Matrix> units;
  for (Index k = 0; k < network.output_dim(); ++k) {
    Matrix unit = Matrix::Zero(network.output_dim(), x.cols());
    unit.row(k).setOnes();
    const Matrix rows = network.per_sample_gradients(*cache, unit);
    for (Index b = 0; b < x.cols(); ++b) {
      const auto output_k = [&](const Vector& theta) {
        example::ResidualNetwork copy = network;
        copy.set_parameters(theta);
        return Vector::Constant(1, copy.forward(x.col(b))(k, 0));
      };
      const Matrix fd = physgrad::finite_difference_jacobian(output_k, network.parameters());
      error = std::max(error, (rows.row(b) - fd.row(0)).cwiseAbs().maxCoeff());
    }
    error = std::max(error, (network.backward(*cache, unit) - rows.colwise().sum().transpose())
                                .cwiseAbs()
                                .maxCoeff());
    units.push_back(unit);
  }
  const Matrix factored = network.per_sample_gram(*cache, units);
  const Matrix formed = network.Network::per_sample_gram(*cache, units);
  return std::max(error, (factored - formed).cwiseAbs().maxCoeff() / formed.cwiseAbs().maxCoeff());
}

}  // namespace

int main() {
  const example::PendulumConfig config;
  const example::Pendulum pendulum(config);
  example::ResidualNetwork network(4, 32, config.steps);
  network.initialize(7);

  const double error = derivative_error(network);
  std::printf("network derivatives vs finite differences: max error %.1e (%s)\n", error,
              error < 1e-6 ? "passed" : "FAILED");
  if (!(error < 1e-6)) return 1;

  const physgrad::Dataset train_set = example::make_pendulum_tasks(512, 1);
  const physgrad::Dataset test_set = example::make_pendulum_tasks(128, 2);
  const physgrad::L2Loss loss;
  physgrad::TrainerOptions options;
  options.batch_size = 32;
  options.max_iterations = 400;
  for (const auto& [id, lr] : {std::pair{"adam", 1e-2}, std::pair{"hig", 1.0}}) {
    example::ResidualNetwork trained = network;  // the same start for both rules
    const auto update = physgrad::make_learning_update(id, {{"lr", lr}});
    const physgrad::TrainingSummary summary =
        physgrad::train(trained, *update, {&pendulum, &loss}, train_set, &test_set, options);
    std::printf("%-4s final loss %.3e (test %.3e, start %.3e), %lld iterations, %.2f s\n", id,
                summary.history.back().train_loss, summary.history.back().test_loss,
                summary.history.front().train_loss, summary.iterations, summary.train_seconds);
  }
  return 0;
}
