// Benchmark results as bench_report reads them — the Google Benchmark JSON of physgrad_bench by
// name (CPU and wall milliseconds per iteration, label, counters), and numbers as the tables
// show them.
#pragma once

#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace physgrad::bench {

using nlohmann::json;

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
inline std::string ms_text(std::optional<double> ms) {
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

inline std::string number(double value, const char* format = "%.3g") {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

inline std::string ratio_text(std::optional<double> a, std::optional<double> b) {
  return a && b && *b > 0 ? number(*a / *b, "%.2f") + "×" : "–";
}

inline const char* backend_name(double code) {
  return code == 0 ? "svd" : code == 1 ? "gram" : code == 2 ? "normal" : "–";
}

}  // namespace physgrad::bench
