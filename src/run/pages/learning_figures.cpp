// LearningSweep's presentation: runs grouped per rule, loss and metric figures (median and band
// over seeds); its tables are in learning_tables.cpp.
#include <algorithm>
#include <cmath>

#include "physgrad/run/cases/learning_runs.hpp"
#include "physgrad/run/pages/learning_verdict.hpp"
#include "physgrad/run/cases/rule_colors.hpp"
#include "physgrad/report/line_plot.hpp"
#include "physgrad/report/seed_band.hpp"
#include "physgrad/report/svg_document.hpp"

namespace physgrad::run {

void mark_if_diverging(Series& series) {
  if (series.y.size() > 1 && series.y.back() > series.y.front()) {
    series.sets_range = false;
    series.end_label =
        "diverging: ends at ×" + format_value(series.y.back() / series.y.front()) + " its start";
  }
}

Series held_controls(const std::string& label, const Vector& u, double dt,
                     const std::string& color) {
  Series s{label, {}, std::vector<double>(u.data(), u.data() + u.size()), color};
  for (Index k = 0; k <= u.size(); ++k) s.x.push_back(dt * static_cast<double>(k));
  if (u.size() > 0) s.y.push_back(s.y.back());
  s.steps = true;
  return s;
}

std::vector<const LearningResult*> LearningSweep::first_seed_runs(const std::string& tag) const {
  std::vector<const LearningResult*> runs;
  for (const LearningResult& r : results_) {
    const bool seen = std::any_of(runs.begin(), runs.end(),
                                  [&](const LearningResult* other) { return other->id == r.id; });
    if (r.tag == tag && !seen) runs.push_back(&r);
  }
  return runs;
}

std::vector<std::vector<const LearningResult*>> LearningSweep::rule_groups(
    const std::string& tag) const {
  std::vector<std::vector<const LearningResult*>> groups;
  for (const LearningResult& r : results_) {
    if (r.tag != tag) continue;
    const auto group = std::find_if(groups.begin(), groups.end(), [&](const auto& g) {
      return g.front()->id == r.id;
    });
    if (group == groups.end()) {
      groups.push_back({&r});
    } else {
      group->push_back(&r);
    }
  }
  return groups;
}

void LearningSweep::add_metric_figure(RunContext& context,
                                      const std::vector<std::vector<const LearningResult*>>& groups,
                                      const std::string& file, const std::string& title,
                                      const std::string& y_label,
                                      const std::function<double(const TrainingRecord&)>& value,
                                      Progress progress, bool log_y) {
  context.add_figure(metric_figure(groups, file, title, y_label, value, progress, log_y));
}

RunContext::Figure LearningSweep::metric_figure(
    const std::vector<std::vector<const LearningResult*>>& groups, const std::string& file,
    const std::string& title, const std::string& y_label,
    const std::function<double(const TrainingRecord&)>& value, Progress progress, bool log_y,
    std::optional<std::pair<double, double>> y_range) {
  std::vector<Series> series;
  bool several_seeds = false;
  for (const auto& group : groups) {
    std::vector<Curve> curves;
    long long stopped = 0;
    for (const LearningResult* run : group) {
      Curve& c = curves.emplace_back();
      for (const TrainingRecord& r : run->summary.history) {
        c.x.push_back(progress == Progress::kTime    ? r.train_seconds
                      : progress == Progress::kEpoch ? r.epoch
                                                     : static_cast<double>(r.iteration));
        c.y.push_back(value(r));
      }
      stopped += run->summary.termination == TrainingTermination::kNumericalFailure ? 1 : 0;
    }
    const std::size_t n = group.size();
    several_seeds = several_seeds || n > 1;
    const LearningResult& first = *group.front();
    Series s = median_band(first.label + (n > 1 ? ", median of " + std::to_string(n) : ""),
                           curves, color_for(first.id), log_y);
    s.markers = true;
    s.dashed = !pretrained_rule(first.id).empty();  // and a colour of its own (color_for)
    // Over time the seeds are evaluated at different moments: each holds its last value, so
    // median and band change in steps.
    s.steps = n > 1 && progress == Progress::kTime;
    if (log_y) mark_if_diverging(s);
    // Where a pretrained run switched from Adam to its rule (it did when it ran past it).
    const nlohmann::json switch_at = first.params.value("pretrain_iterations", nlohmann::json());
    if (switch_at.is_number_integer() && first.params.value("switched", true) &&
        first.summary.iterations > switch_at.get<long long>()) {
      for (const TrainingRecord& r : first.summary.history) {
        if (r.iteration < switch_at.get<long long>()) continue;
        const double x = progress == Progress::kTime    ? r.train_seconds
                         : progress == Progress::kEpoch ? r.epoch
                                                        : static_cast<double>(r.iteration);
        double y = NAN;  // the drawn curve where the rule took over
        for (std::size_t i = 0; i < s.x.size() && s.x[i] <= x; ++i) y = s.y[i];
        s.marks.push_back({x, y, "switched from Adam after iteration " +
                                     std::to_string(switch_at.get<long long>())});
        break;
      }
    }
    if (stopped > 0) {
      s.end_label = n > 1 ? std::to_string(stopped) + " of " + std::to_string(n) +
                                " runs stopped: not finite"
                          : "stopped: not finite after iteration " +
                                std::to_string(first.summary.iterations);
    }
    series.push_back(std::move(s));
  }
  LinePlotOptions options;
  options.title = title;
  options.x_label = progress == Progress::kTime    ? "training time (s, evaluations excluded)"
                    : progress == Progress::kEpoch ? "epoch"
                                                   : "iteration";
  options.y_label = y_label;
  options.log_y = log_y;
  options.y_range = y_range;
  // Rules that run for one time budget can end hundreds of iterations apart (HIG's step costs
  // what hundreds of Adam steps do): a log x axis keeps the shorter runs visible. Runs that
  // stopped or diverged (an end label) do not count.
  double shortest = 0, longest = 0;
  for (const Series& s : series) {
    if (s.x.empty() || !s.end_label.empty()) continue;
    shortest = shortest == 0 ? s.x.back() : std::min(shortest, s.x.back());
    longest = std::max(longest, s.x.back());
  }
  options.log_x = progress != Progress::kTime && shortest > 0 && longest >= 10 * shortest;
  const std::string caption =
      title + ". " +
      (several_seeds ? "Line: median over the seeds; band: their minimum to maximum. " : "") +
      "Dots: evaluations." +
      (options.log_x ? " Log x axis (the start is not drawn): the rules ran " +
                           format_value(shortest) + " to " + format_value(longest) + " " +
                           options.x_label + "s in the same budget."
                     : "");
  return {file, caption, line_plot_svg(series, options),
          groups.empty() ? std::string() : groups.front().front()->tag};
}

void LearningSweep::add_loss_figures(RunContext& context, const std::string& tag,
                                     const std::string& file_tag, bool by_epoch,
                                     const std::string& loss_label) const {
  const auto test_loss = [](const TrainingRecord& r) { return r.test_loss; };
  const auto groups = rule_groups(tag);
  for (const Progress progress :
       {by_epoch ? Progress::kEpoch : Progress::kIteration, Progress::kTime}) {
    const std::string axis = progress == Progress::kTime    ? "time"
                             : progress == Progress::kEpoch ? "epoch"
                                                            : "iteration";
    add_metric_figure(context, groups, "loss_vs_" + axis + "_" + file_tag + ".svg",
                      "Test loss vs " +
                          std::string(progress == Progress::kTime ? "training time" : axis) +
                          " (" + tag + ")",
                      loss_label, test_loss, progress);
  }
}

RunContext::Figure LearningSweep::progress_figure(
    const std::string& tag, const std::string& file,
    const std::function<double(const TrainingRecord&)>& value, const std::string& what,
    const std::string& y_label) const {
  const auto groups = rule_groups(tag);
  const std::string title = what + " (" + tag + ")";
  std::vector<std::string> panels;
  for (const Progress progress : {Progress::kIteration, Progress::kTime}) {
    panels.push_back(metric_figure(groups, "", title + (progress == Progress::kTime
                                                            ? " per second of training"
                                                            : " per update"),
                                   y_label, value, progress, true)
                         .svg);
  }
  return {file,
          "The message metric per update (left) and per second of training (right), " + tag +
              ": the same runs against the updates they made and the training time they took.",
          svg::side_by_side(panels), tag};
}

void LearningSweep::set_time_message(const std::string& tag, const std::string& file_tag,
                                     const std::string& what) const {
  const auto test_loss = [](const TrainingRecord& r) { return r.test_loss; };
  const std::string file = "progress_" + file_tag + ".svg";
  context_.add_figure(progress_figure(tag, file, test_loss, "Test loss", "mean test loss"));
  context_.set_message(file,
                       verdict_after("After the same budget, ",
                                     verdict_sentence({rule_groups(tag), test_loss, what})),
                       {"test_loss", what, labels(tag)});
}

void LearningSweep::set_metric_message(const std::string& tag, const std::string& file,
                                       const std::string& metric, const std::string& what_metric,
                                       const std::string& loss_lead, const std::string& what_loss,
                                       const std::string& prefix) const {
  const auto test_loss = [](const TrainingRecord& r) { return r.test_loss; };
  context_.set_message(
      file,
      verdict_after(prefix, verdict_sentence({rule_groups(tag), extra(metric), what_metric})) +
          " " + loss_lead + ": " + verdict_sentence({rule_groups(tag), test_loss, what_loss}),
      {metric, what_metric, labels(tag)});
}

std::function<double(const TrainingRecord&)> LearningSweep::extra(const std::string& key) {
  return [key](const TrainingRecord& r) { return r.extras.at(key).get<double>(); };
}

std::vector<std::string> LearningSweep::labels(const std::string& tag) const {
  std::vector<std::string> out;
  for (const LearningResult& r : results_) {
    if (r.tag == tag && std::find(out.begin(), out.end(), r.label) == out.end()) {
      out.push_back(r.label);
    }
  }
  return out;
}

}  // namespace physgrad::run
