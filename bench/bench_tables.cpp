#include "bench_tables.hpp"

#include <cmath>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace physgrad::bench {

namespace {

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

}  // namespace

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

}  // namespace physgrad::bench
