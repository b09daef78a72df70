#include "heat_inverse_figures.hpp"

#include <algorithm>
#include <string>

#include "physgrad/catalogue.hpp"
#include "physgrad/run/cases/rule_colors.hpp"
#include "physgrad/report/field_plot.hpp"
#include "physgrad/report/line_plot.hpp"

namespace physgrad::experiments {

namespace {

// The cell values of column k, the last one repeated at the right end of the last cell.
std::vector<double> heat_line_cells(const Matrix& m, Index k) {
  std::vector<double> v(m.col(k).data(), m.col(k).data() + m.rows());
  v.push_back(v.back());
  return v;
}

// Every trained network's predictions for the whole test set, computed once: a network with
// batch norm normalises with the statistics of the batch it is given, so a sample is shown as
// the test evaluation saw it.
std::vector<Matrix> heat_predictions(const TrainedNetworks& trained, const Matrix& inputs) {
  std::vector<Matrix> out;
  for (const auto& entry : trained) out.push_back(entry.second->forward(inputs));
  return out;
}

}  // namespace

void add_line_reconstructions(run::RunContext& context, const Matrix& truth, const Matrix& inputs,
                              const TrainedNetworks& trained, Index count) {
  const Index n = truth.rows();
  std::vector<double> edges(static_cast<std::size_t>(n) + 1);
  for (Index i = 0; i <= n; ++i) edges[static_cast<std::size_t>(i)] = static_cast<double>(i);
  const std::vector<Matrix> predicted = heat_predictions(trained, inputs);
  for (Index k = 0; k < std::min(count, truth.cols()); ++k) {
    std::vector<Series> series = {
        {"x* (true initial state)", edges, heat_line_cells(truth, k), "#d62728"},
        {"y* = P(x*) (network input)", edges, heat_line_cells(inputs, k), "#9e9e9e", false,
         true}};
    std::string losses;
    for (std::size_t r = 0; r < trained.size(); ++r) {
      const run::LearningResult* run = trained[r].first;
      const Matrix x = predicted[r].col(k);
      const double x_loss = 0.5 * (x - truth.col(k)).squaredNorm();
      series.push_back({run->label, edges, heat_line_cells(x, 0), color_for(run->id)});
      losses += (losses.empty() ? "" : ", ") + run->label + " " + run::format_value(x_loss);
    }
    for (Series& s : series) s.steps = true;
    LinePlotOptions options;
    options.x_range = {{0.0, static_cast<double>(n)}};
    options.title = "Test sample " + std::to_string(k + 1) + ": true and reconstructed x";
    options.x_label = "cell (periodic, " + std::to_string(n) + " cells)";
    options.y_label = "temperature";
    context.add_figure({"reconstruction_" + std::to_string(k + 1) + ".svg",
                        options.title + " after training, one step per cell. x loss ½‖x − x*‖²: " +
                            losses + ".",
                        line_plot_svg(series, options)});
  }
}

void add_field_reconstructions(run::RunContext& context, Index n, const Matrix& truth,
                               const Matrix& inputs, const TrainedNetworks& trained, Index count,
                               const FieldWords& words) {
  const auto grid = [n](const Vector& field) {
    return cell_grid(static_cast<int>(n), {field.data(), field.data() + field.size()});
  };
  const std::vector<Matrix> predicted = heat_predictions(trained, inputs);
  for (Index k = 0; k < std::min(count, truth.cols()); ++k) {
    std::vector<FieldPanel> panels = {{"x* (true)", grid(truth.col(k))},
                                      {"y* = P(x*)", grid(inputs.col(k))}};
    std::string losses;
    for (std::size_t r = 0; r < trained.size(); ++r) {
      const run::LearningResult* run = trained[r].first;
      const Vector x = predicted[r].col(k);
      panels.push_back({learning_run_label(run->id), grid(x)});
      losses += (losses.empty() ? "" : ", ") + run->label + " " +
                run::format_value(0.5 * (x - truth.col(k)).squaredNorm());
    }
    FieldPanelsOptions options;
    options.title =
        "Test sample " + std::to_string(k + 1) + ": true, " + words.input + " and reconstructed";
    options.x_label = "cell i";
    options.y_label = "cell j";
    options.value_label = words.value;
    options.panel_width = 150;
    context.add_figure({"sample_" + std::to_string(k + 1) + ".svg",
                        options.title + " fields in one colour range. x loss ½‖x − x*‖²: " +
                            losses + ".",
                        field_panels_svg(panels, options)});
  }
}

}  // namespace physgrad::experiments
