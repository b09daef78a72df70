// bench_report RESULTS.json PERFORMANCE.md FIGURE.svg — turns the Google Benchmark output of
// physgrad_bench into the tables between "<!-- bench:begin -->" and "<!-- bench:end -->" of
// PERFORMANCE.md (the rest of the file is kept) and the size-sweep figure (step time against
// B·m, one line per |θ|). Exit 1 with a message when a file cannot be read or written.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/io/atomic_file.hpp"
#include "physgrad/report/colors.hpp"
#include "physgrad/report/line_plot.hpp"

namespace {

using nlohmann::json;

const std::string kBegin = "<!-- bench:begin -->";
const std::string kEnd = "<!-- bench:end -->";

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw physgrad::Error("cannot read " + path);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

// One benchmark run: its CPU time per iteration in milliseconds (one BLAS thread, so the work
// itself; the wall time on a shared machine adds the waits for a core), its wall time, label
// and counters.
struct Entry {
  double ms = 0;
  double wall_ms = 0;
  std::string label;
  json fields;
};

class Results {
 public:
  explicit Results(const json& document) {
    for (const json& b : document.at("benchmarks")) {
      if (b.value("run_type", "iteration") != "iteration") continue;
      const std::string unit = b.value("time_unit", "ns");
      const double scale = unit == "s" ? 1e3 : unit == "ms" ? 1.0 : unit == "us" ? 1e-3 : 1e-6;
      std::string name = b.at("name").get<std::string>();
      // "learning_step/3/2/iterations:1" → "learning_step/3/2"
      if (const auto cut = name.find("/iterations:"); cut != std::string::npos) name.resize(cut);
      if (const auto cut = name.find("/repeats:"); cut != std::string::npos) name.resize(cut);
      if (const auto cut = name.find("/real_time"); cut != std::string::npos) name.resize(cut);
      entries_[name] = {b.at("cpu_time").get<double>() * scale,
                        b.at("real_time").get<double>() * scale, b.value("label", ""), b};
    }
  }
  const Entry* find(const std::string& name) const {
    const auto found = entries_.find(name);
    return found == entries_.end() ? nullptr : &found->second;
  }
  std::optional<double> ms(const std::string& name) const {
    const Entry* e = find(name);
    return e ? std::optional<double>(e->ms) : std::nullopt;
  }
  std::optional<double> wall_ms(const std::string& name) const {
    const Entry* e = find(name);
    return e ? std::optional<double>(e->wall_ms) : std::nullopt;
  }
  double counter(const std::string& name, const std::string& key) const {
    const Entry* e = find(name);
    return e && e->fields.contains(key) ? e->fields.at(key).get<double>() : NAN;
  }
  const std::map<std::string, Entry>& entries() const { return entries_; }

 private:
  std::map<std::string, Entry> entries_;
};

// 3 significant digits: 0.0934, 4.00, 34.7, 1160.
std::string ms_text(std::optional<double> ms) {
  if (!ms) return "–";
  char buffer[32];
  const double v = *ms;
  if (v >= 100) {
    std::snprintf(buffer, sizeof buffer, "%.0f", v);
  } else if (v >= 10) {
    std::snprintf(buffer, sizeof buffer, "%.1f", v);
  } else if (v >= 1) {
    std::snprintf(buffer, sizeof buffer, "%.2f", v);
  } else {
    std::snprintf(buffer, sizeof buffer, "%.3g", v);
  }
  return std::string(buffer) + " ms";
}

std::string number(double value, const char* format = "%.3g") {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

std::string ratio_text(std::optional<double> a, std::optional<double> b) {
  return a && b && *b > 0 ? number(*a / *b, "%.2f") + "×" : "–";
}

const char* backend_name(double code) {
  return code == 0 ? "svd" : code == 1 ? "gram" : code == 2 ? "normal" : "–";
}

struct Case {
  const char* index;
  const char* title;
};
const std::vector<Case> kCases = {{"0", "hig-toy B 128"},
                                  {"1", "oscillators B 128"},
                                  {"4", "quantum-dipole B 16"},
                                  {"2", "poisson B 16"},
                                  {"3", "poisson B 64"}};

std::string shape(const Results& r, const std::string& step) {
  const double rows = r.counter(step, "rows"), cols = r.counter(step, "cols");
  if (std::isnan(rows)) return "–";
  return number(rows, "%.0f") + " × " + number(cols, "%.0f");
}

std::string reference_table(const Results& r) {
  std::ostringstream out;
  out << "| benchmark |";
  for (const Case& c : kCases) out << ' ' << c.title << " |";
  out << "\n|---|";
  for (std::size_t i = 0; i < kCases.size(); ++i) out << "---|";
  out << '\n';
  const auto row = [&](const std::string& title, const auto& cell) {
    out << "| " << title << " |";
    for (const Case& c : kCases) out << ' ' << cell(std::string(c.index)) << " |";
    out << '\n';
  };
  row("J (B·m × \\|θ\\|)", [&](const std::string& i) {
    const std::string s = shape(r, "gram_matrix/" + i + "/1");
    return s != "–" ? s : shape(r, "learning_step/" + i + "/2");
  });
  row("J Jᵀ formed (J, then dsyrk)",
      [&](const std::string& i) { return ms_text(r.ms("gram_matrix/" + i + "/0")); });
  row("dsyrk alone on a formed J",
      [&](const std::string& i) { return ms_text(r.ms("gram_matrix/" + i + "/2")); });
  row("J Jᵀ from the layer factors",
      [&](const std::string& i) { return ms_text(r.ms("gram_matrix/" + i + "/1")); });
  const char* rules[] = {"Adam", "Gauss-Newton", "HIG", "SIP"};
  for (int rule = 0; rule < 4; ++rule) {
    row(std::string("whole ") + rules[rule] + " step", [&](const std::string& i) {
      return ms_text(r.ms("learning_step/" + i + "/" + std::to_string(rule)));
    });
  }
  row("HIG backend (kept rank)", [&](const std::string& i) {
    const std::string name = "learning_step/" + i + "/2";
    if (!r.find(name)) return std::string("–");
    return std::string(backend_name(r.counter(name, "backend"))) + " (" +
           number(r.counter(name, "rank"), "%.0f") + ")";
  });
  row("dsyevd of a B·m × B·m matrix", [&](const std::string& i) {
    const double rows = r.counter("learning_step/" + i + "/2", "rows");
    if (std::isnan(rows)) return std::string("–");
    return ms_text(r.ms("reference_eigendecomposition/" + number(rows, "%.0f")));
  });
  return out.str();
}

std::string ratios(const Results& r) {
  std::ostringstream out;
  const auto osc_step = r.ms("learning_step/1/2");
  const auto osc_eig = r.ms("reference_eigendecomposition/512");
  out << "- Oscillators (B 128, J 512 × 2956): the whole HIG step costs "
      << ratio_text(osc_step, osc_eig) << " the dsyevd of a 512 × 512 matrix ("
      << ms_text(osc_step) << " / " << ms_text(osc_eig) << "; target ≤ 2×"
      << (osc_step && osc_eig ? (*osc_step <= 2 * *osc_eig ? ", met" : ", NOT met") : "")
      << ").\n";
  const auto syrk = r.ms("gram_matrix/3/2"), factored = r.ms("gram_matrix/3/1");
  out << "- Poisson (B 64, J 4096 × 24 896): J Jᵀ from the layer factors is "
      << ratio_text(syrk, factored) << " faster than the dsyrk on the formed J alone ("
      << ms_text(factored) << " vs " << ms_text(syrk) << "; target ≥ 20×"
      << (syrk && factored ? (*syrk >= 20 * *factored ? ", met" : ", NOT met") : "")
      << "), " << ratio_text(r.ms("gram_matrix/3/0"), factored)
      << " faster than forming J and then its dsyrk. The remaining dsyevd of 4096 × 4096 takes "
      << ms_text(r.ms("reference_eigendecomposition/4096")) << "; the whole HIG step "
      << ms_text(r.ms("learning_step/3/2")) << ".\n";
  for (const Case& c : {kCases[1], kCases[3]}) {
    const std::string i = c.index;
    out << "- " << c.title << ": factored vs formed J Jᵀ "
        << ratio_text(r.ms("gram_matrix/" + i + "/0"), r.ms("gram_matrix/" + i + "/1")) << ".\n";
  }
  for (const Case& c : {kCases[2], kCases[1]}) {
    const std::string one = "learning_step_threads/" + std::string(c.index) + "/1";
    const std::string two = "learning_step_threads/" + std::string(c.index) + "/2";
    if (!r.find(one) || !r.find(two)) continue;
    out << "- " << c.title << ", HIG step with the m physics VJPs on 2 threads instead of 1 "
        << "(wall time): " << ms_text(r.wall_ms(two)) << " vs " << ms_text(r.wall_ms(one))
        << " (" << ratio_text(r.wall_ms(one), r.wall_ms(two)) << " faster).\n";
  }
  const auto toy_adam = r.ms("learning_step/0/0"), toy_hig = r.ms("learning_step/0/2");
  out << "- hig-toy: J has 30 columns, so HIG takes the normal path (30 × 30); its step is "
      << ratio_text(toy_hig, toy_adam) << " an Adam step.\n";
  return out.str();
}

std::string eigen_route_table(const Results& r) {
  std::ostringstream out;
  out << "| Gram matrix of | n | kept rank | dsyevd | dsyevr above the cutoff | dsytrd + QL "
         "(tridiagonal) | dsyevr / dsyevd | tridiagonal / dsyevd | relative difference to "
         "dsyevd: dsyevr, tridiagonal |\n|---|---|---|---|---|---|---|---|---|\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"1/64", "oscillators B 64"},  {"1/128", "oscillators B 128"},
      {"1/256", "oscillators B 256"}, {"2/4", "poisson B 4"},
      {"2/16", "poisson B 16"},      {"2/64", "poisson B 64"},
      {"4/16", "quantum-dipole B 16"}, {"4/64", "quantum-dipole B 64"}};
  for (const auto& [key, title] : cases) {
    const std::string full = "eigen_route/" + key + "/0", subset = "eigen_route/" + key + "/1",
                      tridiagonal = "eigen_route/" + key + "/5";
    if (!r.find(full) || !r.find(subset) || !r.find(tridiagonal)) continue;
    out << "| " << title << " | " << number(r.counter(full, "n"), "%.0f") << " | "
        << number(r.counter(full, "rank"), "%.0f") << " | " << ms_text(r.ms(full)) << " | "
        << ms_text(r.ms(subset)) << " | " << ms_text(r.ms(tridiagonal)) << " | "
        << ratio_text(r.ms(subset), r.ms(full)) << " | "
        << ratio_text(r.ms(tridiagonal), r.ms(full)) << " | "
        << number(r.counter(full, "rel_diff"), "%.1e") << ", "
        << number(r.counter(tridiagonal, "rel_diff"), "%.1e") << " |\n";
  }
  return out.str();
}

std::string lanczos_table(const Results& r) {
  std::ostringstream out;
  out << "| Gram matrix of | n | kept rank | dsyevd | Lanczos steps k | Lanczos time | relative "
         "error |\n|---|---|---|---|---|---|---|\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"1/128", "oscillators B 128"}, {"2/16", "poisson B 16"}, {"4/64", "quantum-dipole B 64"}};
  for (const auto& [key, title] : cases) {
    for (const int k : {32, 128, 512}) {
      const std::string name = "lanczos_route/" + key + "/" + std::to_string(k);
      if (!r.find(name)) continue;
      const std::string full = "eigen_route/" + key + "/0";
      out << "| " << title << " | " << number(r.counter(name, "n"), "%.0f") << " | "
          << number(r.counter(full, "rank"), "%.0f") << " | " << ms_text(r.ms(full)) << " | " << k
          << " | " << ms_text(r.ms(name)) << " | " << number(r.counter(name, "rel_err"), "%.1e")
          << " |\n";
    }
  }
  return out.str();
}

std::string backends(const Results& r) {
  std::ostringstream out;
  out << "Pseudo-inverse backends on a random J (κ = ½): 512 × 2956 SVD (dgesdd) "
      << ms_text(r.ms("power_pinv_backend/512/2956/1")) << ", Gram path "
      << ms_text(r.ms("power_pinv_backend/512/2956/2")) << "; 1024 × 24 896 Gram path "
      << ms_text(r.ms("power_pinv_backend/1024/24896/2")) << ". dsyevd alone: ";
  bool first = true;
  for (const int n : {256, 448, 512, 1024, 4096}) {
    const auto t = r.ms("reference_eigendecomposition/" + std::to_string(n));
    if (!t) continue;
    out << (first ? "" : ", ") << n << ": " << ms_text(t);
    first = false;
  }
  out << ".\n";
  return out.str();
}

struct Sweep {
  std::vector<int> batches, widths;
  std::map<std::pair<int, int>, std::string> names;
};

Sweep sweep_of(const Results& r) {
  Sweep s;
  std::set<int> batches, widths;
  for (const auto& [name, entry] : r.entries()) {
    int b = 0, h = 0;
    if (std::sscanf(name.c_str(), "size_sweep/%d/%d", &b, &h) == 2) {
      batches.insert(b);
      widths.insert(h);
      s.names[{b, h}] = name;
    }
  }
  s.batches.assign(batches.begin(), batches.end());
  s.widths.assign(widths.begin(), widths.end());
  return s;
}

std::string sweep_table(const Results& r, const Sweep& s) {
  std::ostringstream out;
  out << "| B·m \\ \\|θ\\| |";
  for (const int h : s.widths) {
    const auto found = s.names.find({s.batches.front(), h});
    out << ' ' << number(r.counter(found->second, "cols"), "%.0f") << " (h " << h << ") |";
  }
  out << "\n|---|";
  for (std::size_t i = 0; i < s.widths.size(); ++i) out << "---|";
  out << '\n';
  for (const int b : s.batches) {
    out << "| " << 64 * b << " |";
    for (const int h : s.widths) {
      const auto found = s.names.find({b, h});
      if (found == s.names.end()) {
        out << " – |";
        continue;
      }
      out << ' ' << ms_text(r.ms(found->second)) << ' '
          << backend_name(r.counter(found->second, "backend")) << " |";
    }
    out << '\n';
  }
  return out.str();
}

std::string sweep_figure(const Results& r, const Sweep& s) {
  std::vector<physgrad::Series> series;
  for (const int h : s.widths) {
    physgrad::Series line;
    for (const int b : s.batches) {
      const auto found = s.names.find({b, h});
      if (found == s.names.end()) continue;
      line.label = "HIG step, |θ| = " + number(r.counter(found->second, "cols"), "%.0f");
      line.x.push_back(64.0 * b);
      line.y.push_back(r.ms(found->second).value() / 1e3);
    }
    line.markers = true;
    series.push_back(std::move(line));
  }
  physgrad::Series eig{"dsyevd of B·m × B·m alone", {}, {}, "#000000", true, true, {}, {}};
  for (const int n : {256, 448, 512, 1024, 4096}) {
    const auto t = r.ms("reference_eigendecomposition/" + std::to_string(n));
    if (!t) continue;
    eig.x.push_back(n);
    eig.y.push_back(*t / 1e3);
  }
  series.push_back(std::move(eig));
  physgrad::LinePlotOptions options;
  options.title = "HIG step on the Poisson problem vs B·m (64-h-2h-h-64 network)";
  options.x_label = "B·m (rows of J)";
  options.y_label = "seconds per step";
  options.log_x = true;
  options.log_y = true;
  return physgrad::line_plot_svg(series, options);
}

std::string machine_line(const json& context) {
  std::ostringstream out;
  out << "Run of " << context.value("date", "?") << " on " << context.value("num_cpus", 0)
      << " CPUs";
  if (context.contains("load_avg") && !context.at("load_avg").empty()) {
    out << ", load average at the start " << number(context.at("load_avg")[0].get<double>(), "%.2f");
  }
  if (context.contains("blas_core")) {
    out << ", OpenBLAS kernels " << context.at("blas_core").get<std::string>();
  }
  out << "; CPU time per iteration (one BLAS thread).";
  return out.str();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::cerr << "usage: bench_report RESULTS.json PERFORMANCE.md FIGURE.svg\n";
    return 2;
  }
  try {
    const json document = json::parse(read_text(argv[1]));
    const Results results(document);
    const Sweep sweep = sweep_of(results);
    std::string doc = read_text(argv[2]);
    const auto begin = doc.find(kBegin), end = doc.find(kEnd);
    if (begin == std::string::npos || end == std::string::npos || end < begin) {
      throw physgrad::Error(std::string(argv[2]) + " has no " + kBegin + " … " + kEnd + " block");
    }
    std::ostringstream block;
    block << kBegin << "\n<!-- generated by bench_report from bench/results.json -->\n"
          << machine_line(document.value("context", json::object())) << "\n\n"
          << reference_table(results) << "\nRatios from this run:\n" << ratios(results) << '\n'
          << backends(results);
    if (!sweep.batches.empty()) {
      const std::string figure = std::string(argv[3]);
      const std::string file = figure.substr(figure.find_last_of('/') + 1);
      block << "\nSize sweep: the HIG step on the Poisson problem (τ 1e-5) with a 64-h-2h-h-64 "
               "tanh network; each cell is the step time and the backend chosen (normal when "
               "B·m > |θ|).\n\n"
            << sweep_table(results, sweep) << "\n![HIG step time against B·m](" << file << ")\n";
      physgrad::write_file_atomic(figure, sweep_figure(results, sweep));
    }
    block << "\nThe eigen part of the Gram path, f(G)·g, on the Gram matrices of the reference "
             "configurations (HIG τ): all eigenpairs (dsyevd), the pairs above the cutoff only "
             "(dsyevr with a value range, λ_max bounded below by a few power steps), and the "
             "tridiagonal eigensolver (dsytrd, then every eigenvalue by QL with its rotations "
             "applied to g; no eigenvector formed):\n\n"
          << eigen_route_table(results)
          << "\nAn explicitly approximate route: f(G)·g from k Lanczos steps (full "
             "reorthogonalization, f applied to the Ritz values above the cutoff), against the "
             "dsyevd result:\n\n"
          << lanczos_table(results);
    doc.replace(begin, end - begin, block.str());
    physgrad::write_file_atomic(argv[2], doc);
  } catch (const std::exception& e) {
    std::cerr << "bench_report: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
