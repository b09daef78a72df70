// Stop requests and sizes in the simulators: every time loop polls the stop flag (a request made
// while a long forward pass runs ends it within milliseconds, a deferred one does not), training
// stopped inside a step keeps the state before it and resumes to the uninterrupted result, and
// every constructor refuses sizes whose dimensions overflow or do not fit in memory.
#include <gtest/gtest.h>

#include <chrono>
#include <limits>
#include <string>
#include <thread>

#include "learning_fixture.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/physics/coupled_oscillators.hpp"
#include "physgrad/physics/fpu_chain.hpp"
#include "physgrad/physics/heat_diffusion.hpp"
#include "physgrad/physics/poisson.hpp"
#include "physgrad/physics/quantum_dipole.hpp"
#include "physgrad/stop.hpp"
#include "physgrad/train/trainer.hpp"

namespace physgrad {
namespace {

// Clears the process-wide flag after each test, so that no other test sees a request.
class Stop : public ::testing::Test {
 protected:
  void SetUp() override { clear_stop_request(); }
  void TearDown() override { clear_stop_request(); }
};

// Calls `call`, which must throw StopRequested with `message`.
template <typename Call>
void expect_stopped(const Call& call, const std::string& message) {
  try {
    call();
    ADD_FAILURE() << "no StopRequested, expected '" << message << "'";
  } catch (const StopRequested& e) {
    EXPECT_EQ(std::string(e.what()), message);
  }
}

TEST_F(Stop, EveryTimeLoopOfTheSimulatorsPollsTheFlag) {
  const FpuChain fpu({.masses = 4, .steps = 50});
  OscillatorConfig initial_state = OscillatorConfig::paper();
  initial_state.input = OscillatorInput::kInitialState;
  const CoupledOscillators oscillators(initial_state);
  const QuantumDipole dipole;
  const HeatDiffusion heat({.n = 16, .dims = 1, .amount = 1});
  const Vector state = Vector::Constant(8, 0.1), controls = Vector::Constant(384, 0.1);
  const Vector psi = dipole_eigenstate(1);

  // Unasked, every call runs to its end.
  EXPECT_NO_THROW(fpu.forward(state));
  EXPECT_NO_THROW(heat.forward(Vector::Ones(16)));
  request_stop();
  EXPECT_TRUE(stop_requested());
  EXPECT_TRUE(stop_request_flag().load());
  expect_stopped([&] { fpu.forward(state); }, "fpu_chain: stopped on request");
  expect_stopped([&] { fpu.vjp_batch(state, Matrix(), state); }, "fpu_chain: stopped on request");
  expect_stopped([&] { fpu.time_reversal(state); }, "fpu_chain: stopped on request");
  expect_stopped([&] { oscillators.forward(Vector::Constant(4, 0.1)); },
                 "coupled_oscillators: stopped on request");
  expect_stopped([&] { oscillators.time_reversal(Vector::Constant(4, 0.1)); },
                 "coupled_oscillators.time_reversal: stopped on request");
  expect_stopped([&] { dipole.forward(controls, psi); }, "quantum_dipole: stopped on request");
  expect_stopped([&] { heat.forward(Vector::Ones(16)); }, "heat_diffusion: stopped on request");
  EXPECT_TRUE(stop_acknowledged());

  // Deferred (training shared by several processes), the polls let every call end.
  {
    const DeferStopPolls defer;
    EXPECT_NO_THROW(fpu.forward(state));
    EXPECT_NO_THROW(dipole.vjp_batch(controls, psi, psi));
    EXPECT_NO_THROW(oscillators.vjp_batch(Vector::Constant(4, 0.1), Matrix(), Vector::Ones(4)));
  }
  EXPECT_THROW(fpu.forward(state), StopRequested);

  clear_stop_request();
  EXPECT_FALSE(stop_acknowledged());
  EXPECT_NO_THROW(fpu.forward(state));
}

// A request made while one long forward pass runs ends it at the next time step: 10⁸ steps of a
// 4-mass chain take over a minute, the stop comes within a fraction of a second of the request.
TEST_F(Stop, ALongForwardPassEndsSoonAfterTheRequest) {
  const FpuChain chain({.masses = 4, .steps = 100'000'000});
  std::thread requester([] {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    request_stop();
  });
  const auto start = std::chrono::steady_clock::now();
  EXPECT_THROW(chain.forward(Vector::Constant(8, 0.1)), StopRequested);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  requester.join();
  EXPECT_GE(seconds, 0.2);
  EXPECT_LT(seconds, 1.0);
}

// The comparison toy, which requests a stop in its `stop_at`-th forward pass over a training
// batch (evaluations take the whole set of `evaluated` samples, SIP's local inverse one) and
// then polls, as a simulator with time steps does.
class StopsInAStep final : public Simulator {
 public:
  StopsInAStep(Index evaluated, int stop_at) : evaluated_(evaluated), stop_at_(stop_at) {}
  std::string name() const override { return "stops_in_a_step"; }
  Index input_dim() const override { return 2; }
  Index output_dim() const override { return 2; }
  Matrix forward_batch(const Matrix& x, const Matrix& context) const override {
    if (x.cols() > 1 && x.cols() != evaluated_ && ++calls_ == stop_at_) request_stop();
    throw_if_stop_requested(name().c_str());
    return inner_.forward_batch(x, context);
  }
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override {
    return inner_.vjp_batch(x, context, gy);
  }
  bool has_inverse() const override { return true; }
  Vector inverse(const Vector& y, const Vector& x0, const Vector& context) const override {
    return inner_.inverse(y, x0, context);
  }

 private:
  ComparisonToy inner_;
  Index evaluated_;
  int stop_at_;
  mutable int calls_ = 0;
};

TEST_F(Stop, TrainingStoppedInsideAStepResumesToTheUninterruptedResult) {
  TrainerOptions options;
  options.batch_size = 8;  // 30 samples: epochs end mid-way
  options.max_iterations = 20;
  options.eval_every = 4;
  for (const std::string& id : rule_ids(RuleKind::kLearning)) {
    testing::NetworkThroughPhysics whole_run(30);
    const auto whole_update = make_learning_update(id, testing::test_settings(id));
    const TrainingSummary whole = train(whole_run.network, *whole_update, whole_run.problem,
                                        whole_run.data, &whole_run.data, options);

    // Stopped in the forward pass of the 7th step; the checkpoint holds the 6 steps before it.
    testing::NetworkThroughPhysics part(30);
    const StopsInAStep stopping(30, 7);
    const LearningProblem stopping_problem{&stopping, &part.loss};
    std::optional<TrainerState> saved;
    TrainerOptions interrupted_options = options;
    interrupted_options.on_checkpoint = [&saved](const TrainerState& state) { saved = state; };
    const auto first = make_learning_update(id, testing::test_settings(id));
    const TrainingSummary interrupted = train(part.network, *first, stopping_problem, part.data,
                                              &part.data, interrupted_options);
    EXPECT_EQ(interrupted.termination, TrainingTermination::kInterrupted) << id;
    EXPECT_EQ(interrupted.message, "stopped on request during iteration 7 (not applied)") << id;
    ASSERT_TRUE(saved.has_value()) << id;
    EXPECT_EQ(saved->summary.iterations, 6) << id;
    EXPECT_TRUE(saved->parameters == part.network.parameters()) << id;
    clear_stop_request();

    testing::NetworkThroughPhysics rest(30);
    TrainerOptions resumed = options;
    resumed.resume = &*saved;
    const auto second = make_learning_update(id, testing::test_settings(id));
    const TrainingSummary summary =
        train(rest.network, *second, rest.problem, rest.data, &rest.data, resumed);
    EXPECT_EQ(summary.iterations, whole.iterations) << id;
    EXPECT_TRUE(rest.network.parameters() == whole_run.network.parameters()) << id;  // every bit
    ASSERT_EQ(summary.history.size(), whole.history.size()) << id;
    for (std::size_t k = 0; k < whole.history.size(); ++k) {
      EXPECT_EQ(summary.history[k].train_loss, whole.history[k].train_loss) << id << " " << k;
    }
  }
}

// Calls `make`, which must throw Error naming `value`.
template <typename Make>
void expect_refused(const Make& make, const std::string& value) {
  try {
    make();
    ADD_FAILURE() << "no Error naming " << value;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(value), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("this process may use"), std::string::npos) << e.what();
  }
}

TEST(SimulatorSizes, DimensionsThatOverflowOrDoNotFitAreRefusedNamingTheValue) {
  constexpr Index kHuge = Index{1} << 62;  // 2·kHuge overflows Index
  expect_refused([] { FpuChain({.masses = kHuge}); }, "fpu_chain: 4611686018427387904 masses");
  expect_refused([] { CoupledOscillators({.oscillators = kHuge}); },
                 "coupled_oscillators: 4611686018427387904 oscillators");
  expect_refused([] { CoupledOscillators({.steps = kHuge}); }, "4611686018427387904 steps");
  expect_refused([] { QuantumDipole({.points = kHuge}); },
                 "quantum_dipole: 4611686018427387904 points");
  expect_refused([] { QuantumDipole({.steps = kHuge}); }, "4611686018427387904 steps");
  expect_refused([] { HeatDiffusion({.n = Index{1} << 32, .dims = 2}); },
                 "heat_diffusion: 4294967296 cells per axis in 2-D");
  expect_refused([] { Poisson(Index{1} << 32); }, "poisson: 4294967296×4294967296 grid");

  // A VJP checks the trajectory it keeps before allocating it: (Nt + 1)·B overflows here.
  const FpuChain long_chain({.masses = 2, .steps = std::numeric_limits<Index>::max()});
  expect_refused([&] { long_chain.vjp_batch(Matrix::Zero(4, 3), Matrix(), Matrix::Zero(4, 3)); },
                 "fpu_chain.vjp: the positions of 2 masses over 9223372036854775807 steps for 3 "
                 "samples");
}

}  // namespace
}  // namespace physgrad
