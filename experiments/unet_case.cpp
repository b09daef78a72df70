#include "unet_case.hpp"

#include <algorithm>
#include <cmath>

#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/memory.hpp"

namespace physgrad::experiments {

std::vector<run::OptionSpec> unet_option_specs(const std::string& padding) {
  using run::integer_option;
  using run::text_option;
  return {
      integer_option("levels", "4", "U-net levels (each halves the grid; n must be a multiple "
                                    "of 2^(levels−1))")
          .at_least(1)
          .at_most(8),
      integer_option("filters", "16", "U-net channels per convolution").at_least(1).at_most(256)
          .quick("4"),
      text_option("batch-norm", "on",
                  "batch norm after every 3×3 convolution, with the batch's own statistics "
                  "(on, as phiml's u_net); the Jacobian rules (gn, hig, kfac, kfac-hig, "
                  "lanczos-gn, lanczos-hig) need off")
          .one_of({"on", "off"}),
      text_option("padding", padding,
                  "the convolutions' padding: zero (phiml, the book) or periodic (phiflow 2.2, "
                  "the SIP repository)")
          .one_of({"zero", "periodic"}),
  };
}

UNetOptions unet_of(const run::Settings& settings, int dims, Index n) {
  UNetOptions options;
  options.dims = dims;
  options.n = n;
  options.levels = static_cast<int>(settings.integer("levels"));
  options.filters = settings.integer("filters");
  options.batch_norm = settings.text("batch-norm") == "on";
  options.padding = settings.text("padding") == "periodic" ? Padding::kPeriodic : Padding::kZero;
  return options;
}

void check_unet(const run::Settings& settings, int dims, Index n) {
  require_memory(unet_sample_bytes(unet_of(settings, dims, n), 0),
                 "--n: " + std::to_string(n) + " cells per axis (one sample's U-net activations)");
  const long long levels = settings.integer("levels");
  const long long factor = 1LL << (levels - 1);
  if (n % factor != 0) {
    throw Error("--levels: " + std::to_string(levels) + " halves the grid " +
                std::to_string(levels - 1) + " times, so n must be a multiple of " +
                std::to_string(factor) + "; n is " + std::to_string(n));
  }
  // An Adam→rule twin (--pretrain) exists only beside a rule checked here.
  for (const std::string& id : settings.texts("optimizers")) {
    if (make_learning_update(id)->need() != UpdateNeed::kStackedJacobian) continue;
    if (settings.text("batch-norm") == "on") {
      throw Error("--optimizers: '" + id + "' needs per-sample Jacobians, which batch norm " +
                  "(the batch's own statistics) does not have; run it with --batch-norm off");
    }
    if (settings.has("batch")) {
      // The output cotangents of every physics output (one per cell) for every sample, twice:
      // a 64×64 kfac-hig run at batch 128 (17 GB of cotangents) was killed at 24 GB. A rule
      // given --samples K holds K of them.
      const double cells = std::pow(static_cast<double>(n), dims);
      double directions = cells;
      if (settings.has("samples")) {
        const nlohmann::json params =
            make_learning_update(id, {{"samples", settings.integer("samples")}})->params();
        if (params.contains("samples")) directions = params.at("samples").get<double>();
      }
      const long long batch = settings.integer("batch");
      const double samples = std::min(static_cast<double>(batch),
                                      static_cast<double>(settings.integer("train-size")));
      require_memory(2 * 8.0 * cells * directions * samples,
                     "--batch: " + std::to_string(batch) + " (the stacked Jacobian of '" + id +
                         "' holds " + std::to_string(static_cast<long long>(directions)) +
                         " output cotangents of every sample's field)");
    }
  }
}

void check_unet_ranks(const run::Settings& settings, const run::RunContext& context) {
  const auto& communicator = context.communicator();
  if (settings.text("batch-norm") == "on" && communicator && communicator->size() > 1) {
    throw Error("--batch-norm: on, under " + std::to_string(communicator->size()) +
                " ranks each rank would normalise its share of a batch with its own statistics; "
                "run with --batch-norm off or in one process");
  }
}

run::LearningExperiment::Shape unet_shape(const UNetOptions& options, Index outputs) {
  const double parameters = static_cast<double>(ConvNetwork::unet(options).num_parameters());
  return {outputs, {}, parameters, parameters};
}

double unet_sample_bytes(const UNetOptions& options, Index data_values) {
  const double cells = std::pow(static_cast<double>(options.n), options.dims);
  const double activations = 16.0 * static_cast<double>(options.filters) * cells;
  return (static_cast<double>(data_values) + activations) * sizeof(double);
}

}  // namespace physgrad::experiments
