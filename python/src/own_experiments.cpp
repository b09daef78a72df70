// A Python script's own learning experiment through the experiment framework (run/): a network
// (an MLP of `widths`, or a U-net or convolution stack, own_network.hpp) maps inputs x to the
// simulator's inputs, trained through the simulator with L = ½‖P(f(x)) − ŷ‖² on samples
// (x, ŷ) = data(count, seed), by each rule of --optimizers; run folders, checkpoints, resume and
// the index as for the reference experiments.
#include <pybind11/stl.h>

#include <algorithm>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "physgrad/error.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/run/cases/learning_experiment.hpp"
#include "physgrad/text.hpp"
#include "own_network.hpp"
#include "python_simulator.hpp"
#include "registry.hpp"

namespace physgrad::python {

namespace {

namespace ex = physgrad::run;

class PythonLearningExperiment final : public ex::LearningExperiment {
 public:
  // Holds the GIL: asks the simulator for its output size (output_dim, else one forward pass).
  // Exactly one of `widths` and `network` (OwnNetwork).
  PythonLearningExperiment(std::string name, std::string description, py::object simulator,
                           const std::optional<std::vector<Index>>& widths, py::object data,
                           std::vector<std::string> optimizers, long long iterations,
                           const py::dict& rules, Index train_size, Index test_size,
                           const py::object& network)
      : LearningExperiment({.eval_every = std::to_string(std::max(1LL, iterations / 10))}),
        name_(std::move(name)), description_(std::move(description)),
        simulator_(std::move(simulator)),
        network_(widths, network, "LearningExperiment " + name_), data_(std::move(data)),
        optimizers_(std::move(optimizers)), iterations_(iterations),
        train_size_(train_size), test_size_(test_size) {
    if (name_.empty()) throw Error("LearningExperiment: the name is empty");
    // The name names run folders (runs/NAME-<time>): no path of its own.
    if (name_.find('/') != std::string::npos || name_.find('\\') != std::string::npos ||
        name_.find("..") != std::string::npos || name_.find('\0') != std::string::npos) {
      throw Error("LearningExperiment: the name '" + name_ +
                  "' holds '/', '\\' or '..' (it names run folders)");
    }
    if (iterations_ < 1) {
      throw Error("LearningExperiment " + name_ + ": iterations must be ≥ 1, got " +
                  std::to_string(iterations_));
    }
    if (!PyCallable_Check(data_.ptr())) {
      throw Error("LearningExperiment " + name_ + ": data is not callable");
    }
    CallbackErrors errors;
    try {
      outputs_ = PythonSimulator(simulator_, network_.output_dim(), -1,
                                 Vector::Zero(network_.output_dim()), errors)
                     .output_dim();
    } catch (const CallbackFailed&) {
      raise_kept(errors, "LearningExperiment " + name_);
    }
    read_rules(rules);
    network_.check_rules(optimizers_, "LearningExperiment " + name_ + ": optimizers: ");
    definition_ = definition_text();
  }

  std::string name() const override { return name_; }
  std::string description() const override { return description_; }
  std::vector<std::string> default_optimizers() const override { return optimizers_; }
  long long default_iterations() const override { return iterations_; }

  // The exception a Python callback raised in the last run of the calling thread, if any
  // (taken: the next run starts without one). Each thread that runs this experiment has its
  // own: one thread's exception is neither lost to another's run nor raised in it. Call it
  // holding the GIL, which guards the map.
  CallbackErrors& errors() const { return errors_[std::this_thread::get_id()]; }

  void run(const ex::Settings& settings, ex::RunContext& context) const override {
    // The simulator holds a reference to a Python object: made and released holding the GIL.
    std::optional<PythonSimulator> physics;
    struct Release {
      std::optional<PythonSimulator>& simulator;
      ~Release() {
        py::gil_scoped_acquire held;
        simulator.reset();
      }
    } release{physics};
    CallbackErrors* errors = nullptr;  // this run's (a map's node: it stays where it is)
    {
      py::gil_scoped_acquire held;
      errors = &this->errors();
      *errors = CallbackErrors{};
      errors->stop_on_interrupt = true;  // Ctrl-C stops the run in order, keeping its checkpoint
      physics.emplace(simulator_, network_.output_dim(), outputs_,
                      Vector::Zero(network_.output_dim()), *errors);
    }
    const L2Loss loss;
    const LearningProblem problem{&*physics, &loss};
    const auto seed = static_cast<std::uint64_t>(settings.integer("seed"));
    const Dataset train_set = samples(settings.integer("train-size"), 2 * seed, *errors);
    const Dataset test_set = samples(settings.integer("test-size"), 2 * seed + 1, *errors);
    ex::LearningSweep sweep(settings, context, rules_);
    for (const std::string& id : sweep.run_ids(settings.texts("optimizers"))) {
      const std::unique_ptr<Network> network = network_.build(seed);
      sweep.run(id, name_, {{"seed", seed}}, *network, problem, train_set, &test_set);
    }
    sweep.add_loss_figures(context, name_, "run");
    sweep.set_time_message(name_, "run");
    sweep.add_tables();
  }

 protected:
  // A resume continues what the script defines now: it must be what the run started with.
  void check(const ex::Settings& settings) const override {
    const std::string recorded = settings.text("definition");
    if (recorded != definition_) {
      throw Error("LearningExperiment " + name_ + ": the definition changed since the run " +
                  "started (" + definition_change(recorded, definition_) +
                  "); continue it with the definition it started with, or start a new run");
    }
    network_.check_rules(settings.texts("optimizers"), "--optimizers: ");
  }

  std::vector<ex::OptionSpec> own_options() const override {
    const auto bytes_each = [this](const ex::Settings&) {
      return network_.sample_bytes(network_.input_dim() + outputs_);
    };
    return {ex::sample_count_option("train-size", std::to_string(train_size_),
                                    "training samples", "16", bytes_each),
            ex::sample_count_option("test-size", std::to_string(test_size_), "test samples",
                                    "8", bytes_each),
            ex::text_option("definition", definition_,
                            "what the script defines (widths or network, simulator, data, "
                            "rules), which a resume must find unchanged")};
  }
  Shape shape(const ex::Settings& /*settings*/) const override {
    return network_.shape(outputs_);
  }

 private:
  // rules {id: {option: value}}, each a learning rule's id with options it takes, in range:
  // refused here, before any run, with an Error naming the key or option.
  void read_rules(const py::dict& rules) {
    const std::vector<std::string> known = rule_ids(RuleKind::kLearning);
    for (const auto& [key, value] : rules) {
      const std::string shown = std::string(py::str(py::repr(key))).substr(0, 80);
      if (!py::isinstance<py::str>(key)) {
        throw Error("LearningExperiment " + name_ + ": rules key " + shown +
                    " is not a rule's name (" + unknown_name_text("rule", shown, known) + ")");
      }
      const std::string id = key.cast<std::string>();
      if (std::find(known.begin(), known.end(), id) == known.end()) {
        throw Error("LearningExperiment " + name_ + ": rules: " +
                    unknown_name_text("rule", id, known));
      }
      if (!py::isinstance<py::dict>(value)) {
        throw Error("LearningExperiment " + name_ + ": rules[" + id + "] is not a dict of options");
      }
      py::dict options = py::reinterpret_borrow<py::dict>(value).attr("copy")();
      ex::RuleDefaults defaults;
      try {
        if (options.contains("batch")) {
          defaults.batch = to_integer(options["batch"], "batch", 1,
                                      std::numeric_limits<int>::max());
          options.attr("pop")("batch");
        }
        defaults.settings = rule_settings(options);
        check_rule_option_names(RuleKind::kLearning, id, defaults.settings);
        make_learning_update(id, defaults.settings);  // a value out of range is refused here
      } catch (const Error& e) {
        throw Error("LearningExperiment " + name_ + ": rules[" + id + "]: " + e.what());
      }
      rule_texts_[id] = std::string(py::str(py::repr(
          py::module_::import("builtins").attr("sorted")(value.attr("items")()))));
      rules_[id] = std::move(defaults);
    }
  }

  // The definition as "part=value; …": widths or network, outputs, the simulator's and data's
  // kinds, and each rule's options (the options of the run are recorded as settings of their
  // own).
  std::string definition_text() const {
    const auto kind = [](const py::object& o) {
      const py::object type = py::type::of(o);
      std::string text = py::str(py::getattr(o, "__qualname__", type.attr("__qualname__")));
      if (py::hasattr(o, "name")) text += " " + std::string(py::str(py::repr(o.attr("name"))));
      return text;
    };
    std::string text = network_.definition();
    text += "; outputs=" + std::to_string(outputs_) + "; simulator=" + kind(simulator_) +
            "; data=" + kind(data_);
    for (const auto& [id, options] : rule_texts_) text += "; rules[" + id + "]=" + options;
    return text;
  }

  // What differs between two definition texts, part by part: "rules[hig] {…} → {…}".
  static std::string definition_change(const std::string& before, const std::string& now) {
    const auto parts = [](const std::string& text) {
      std::map<std::string, std::string> out;
      std::size_t start = 0;
      while (start < text.size()) {
        std::size_t end = text.find("; ", start);
        if (end == std::string::npos) end = text.size();
        const std::string part = text.substr(start, end - start);
        const std::size_t equals = part.find('=');
        out[part.substr(0, equals)] = equals == std::string::npos ? "" : part.substr(equals + 1);
        start = end + 2;
      }
      return out;
    };
    const auto was = parts(before), is = parts(now);
    std::string change;
    std::map<std::string, std::string> all = was;
    all.insert(is.begin(), is.end());
    for (const auto& [key, unused] : all) {
      const auto a = was.find(key), b = is.find(key);
      const std::string old_value = a == was.end() ? "none" : a->second;
      const std::string new_value = b == is.end() ? "none" : b->second;
      if (old_value != new_value) {
        if (!change.empty()) change += ", ";
        change += key + " " + old_value + " → " + new_value;
      }
    }
    return change.empty() ? "'" + before + "' → '" + now + "'" : change;
  }

  // data(count, seed) as a Dataset: its inputs (count, the network's input size) and targets
  // (count, outputs).
  Dataset samples(Index count, std::uint64_t seed, CallbackErrors& errors) const {
    return call_python(errors, "data", [&] {
      const py::object pair = data_(count, seed);
      if (!py::isinstance<py::tuple>(pair) || py::len(pair) != 2) {
        throw Error("LearningExperiment " + name_ + ": data(count, seed) returned " +
                    std::string(py::str(py::repr(pair))).substr(0, 80) +
                    ", expected (inputs, targets)");
      }
      const std::string who = "LearningExperiment " + name_ + ": data";
      Dataset d{to_columns(pair[py::int_(0)], who, "inputs"),
                to_columns(pair[py::int_(1)], who, "targets"), Matrix()};
      const Index inputs = network_.input_dim();
      if (d.inputs.rows() != inputs || d.inputs.cols() != count ||
          d.targets.rows() != outputs_ || d.targets.cols() != count) {
        throw Error(who + " gave inputs (" + std::to_string(d.inputs.cols()) + ", " +
                    std::to_string(d.inputs.rows()) + ") and targets (" +
                    std::to_string(d.targets.cols()) + ", " + std::to_string(d.targets.rows()) +
                    "), expected (" + std::to_string(count) + ", " + std::to_string(inputs) +
                    ") and (" + std::to_string(count) + ", " +
                    std::to_string(outputs_) + ")");
      }
      return d;
    });
  }

  std::string name_, description_;
  py::object simulator_;
  OwnNetwork network_;
  py::object data_;
  std::vector<std::string> optimizers_;
  long long iterations_;
  Index train_size_, test_size_;
  Index outputs_ = 0;
  std::map<std::string, ex::RuleDefaults> rules_;
  std::map<std::string, std::string> rule_texts_;  // each rule's options as given (repr)
  std::string definition_;
  mutable std::map<std::thread::id, CallbackErrors> errors_;
};

// An experiment the Python object owns, lent to a Registry for one call.
class LentExperiment final : public ex::Experiment {
 public:
  explicit LentExperiment(std::shared_ptr<const ex::Experiment> lent) : lent_(std::move(lent)) {}
  std::string name() const override { return lent_->name(); }
  std::string description() const override { return lent_->description(); }
  std::vector<ex::OptionSpec> options() const override { return lent_->options(); }
  std::vector<std::string> optimizer_choices() const override {
    return lent_->optimizer_choices();
  }
  std::vector<std::string> default_optimizers() const override {
    return lent_->default_optimizers();
  }
  long long default_iterations() const override { return lent_->default_iterations(); }
  void validate(const ex::Settings& settings) const override { lent_->validate(settings); }
  void run(const ex::Settings& settings, ex::RunContext& context) const override {
    lent_->run(settings, context);
  }

 private:
  std::shared_ptr<const ex::Experiment> lent_;
};

// The items of `own` (a list or tuple), each a physgrad.LearningExperiment: None, or anything
// else, among them is an Error naming it (pybind11 would cast None to a null holder).
std::vector<std::shared_ptr<PythonLearningExperiment>> own_list(const py::object& own) {
  if (own.is_none()) return {};
  const auto refused = [&own] {
    return Error("experiments: " + std::string(py::str(py::repr(own))).substr(0, 80) +
                 " is not a list of physgrad.LearningExperiment");
  };
  if (!py::isinstance<py::list>(own) && !py::isinstance<py::tuple>(own)) throw refused();
  std::vector<std::shared_ptr<PythonLearningExperiment>> out;
  std::size_t index = 0;
  for (const py::handle item : own) {
    if (!py::isinstance<PythonLearningExperiment>(item)) {
      throw Error(std::string(refused().what()) + " (experiments[" + std::to_string(index) +
                  "] is " + std::string(py::str(py::repr(item))).substr(0, 80) + ")");
    }
    out.push_back(item.cast<std::shared_ptr<PythonLearningExperiment>>());
    if (!out.back()) throw refused();
    ++index;
  }
  return out;
}

}  // namespace

run::Registry registry_with(const py::object& own) {
  std::vector<std::unique_ptr<ex::Experiment>> list = experiments::builtin_experiments();
  for (auto& experiment : own_list(own)) {
    list.push_back(std::make_unique<LentExperiment>(std::move(experiment)));
  }
  return run::Registry(std::move(list));
}

bool own_interrupted(const py::object& own) {
  bool interrupted = false;
  for (const auto& experiment : own_list(own)) {
    interrupted = std::exchange(experiment->errors().interrupted, false) || interrupted;
  }
  return interrupted;
}

std::string own_names(const py::object& own) {
  std::string names;
  for (const auto& experiment : own_list(own)) {
    if (!names.empty()) names += ", ";
    names += '\'';
    names += experiment->name();
    names += '\'';
  }
  return names;
}

void raise_own_callback_error(const py::object& own, const std::string& context) {
  for (const auto& experiment : own_list(own)) {
    CallbackErrors& errors = experiment->errors();
    if (errors.error) raise_kept(errors, context);
  }
}

void bind_own_experiments(py::module_& m) {
  py::class_<PythonLearningExperiment, std::shared_ptr<PythonLearningExperiment>>(
      m, "LearningExperiment",
      "A learning experiment of one's own: a network — `widths` (an MLP, tanh between layers) "
      "or `network` (a dict: {'kind': 'unet' or 'conv', 'n': cells per axis, ...}) — trained "
      "through `simulator` (an object with forward(x), as minimize() takes it) on samples "
      "data(count, seed) -> (inputs (count, network inputs), targets (count, m)), by each rule "
      "of `optimizers`; run, resume and index it with run_experiment, resume_experiment and "
      "write_index, giving it in `experiments`.")
      .def(py::init<std::string, std::string, py::object, const std::optional<std::vector<Index>>&,
                    py::object, std::vector<std::string>, long long, const py::dict&, Index,
                    Index, const py::object&>(),
           py::arg("name"), py::arg("description"), py::arg("simulator"),
           py::arg("widths") = py::none(), py::arg("data") = py::none(),
           py::arg("optimizers") = std::vector<std::string>{"adam", "hig"},
           py::arg("iterations") = 200, py::arg("rules") = py::dict(),
           py::arg("train_size") = 256, py::arg("test_size") = 64, py::kw_only(),
           py::arg("network") = py::none())
      .def_property_readonly("name", &PythonLearningExperiment::name)
      .def("__repr__", [](const PythonLearningExperiment& e) {
        return "LearningExperiment(" + e.name() + ")";
      });
}

}  // namespace physgrad::python
