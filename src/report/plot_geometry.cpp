#include "physgrad/report/plot_geometry.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace physgrad::plot {

namespace {

void append_point(std::string& d, const Point& p) { d += svg::num(p.x) + " " + svg::num(p.y); }

}  // namespace

Box bounds_of(const Box& b) { return svg::grow(b, 6, 6); }

bool clip_segment(Point& a, Point& b, const Box& box) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  if (!std::isfinite(dx) || !std::isfinite(dy)) return false;
  // Liang–Barsky, remembering which edge (left, right, top, bottom) cuts each end.
  double t0 = 0, t1 = 1;
  int edge0 = -1, edge1 = -1;
  const std::array<std::array<double, 2>, 4> pq{
      {{-dx, a.x - box.left}, {dx, box.right - a.x}, {-dy, a.y - box.top}, {dy, box.bottom - a.y}}};
  for (int k = 0; k < 4; ++k) {
    const auto [p, q] = pq[static_cast<std::size_t>(k)];
    if (p == 0) {
      if (q < 0) return false;
      continue;
    }
    const double r = q / p;
    if (p < 0 && r > t0) {
      t0 = r;
      edge0 = k;
    } else if (p > 0 && r < t1) {
      t1 = r;
      edge1 = k;
    }
    if (t0 > t1) return false;
  }
  // A cut point lies on its edge exactly; its other coordinate follows from the slope, which
  // stays accurate when an end is far outside (a diverged iterate at 1e300).
  const Point start = a;
  const auto on_edge = [&](int edge) -> Point {
    const double x_edge = edge == 0 ? box.left : box.right;
    const double y_edge = edge == 2 ? box.top : box.bottom;
    if (edge < 2) {
      return {x_edge, std::clamp(start.y + (x_edge - start.x) * (dy / dx), box.top, box.bottom)};
    }
    return {std::clamp(start.x + (y_edge - start.y) * (dx / dy), box.left, box.right), y_edge};
  };
  if (edge0 >= 0) a = on_edge(edge0);
  if (edge1 >= 0) b = on_edge(edge1);
  return true;
}

std::vector<Polyline> clip(const Polyline& line, const Box& box) {
  std::vector<Polyline> pieces;
  if (line.size() == 1 && svg::inside(line[0], box)) pieces.push_back(line);
  bool continues = false;  // the last piece ends at an uncut vertex
  for (std::size_t k = 1; k < line.size(); ++k) {
    Point a = line[k - 1], b = line[k];
    if (!clip_segment(a, b, box)) {
      continues = false;
      continue;
    }
    if (!continues) pieces.push_back({a});
    pieces.back().push_back(b);
    continues = b.x == line[k].x && b.y == line[k].y;
  }
  return pieces;
}

std::vector<Polyline> to_pixels(const std::vector<double>& x, const std::vector<double>& y,
                                const Scale& sx, const Scale& sy, bool split) {
  std::vector<Polyline> pieces(1);
  for (std::size_t k = 0; k < x.size(); ++k) {
    const Point p{sx(x[k]), sy(y[k])};
    if (std::isfinite(p.x) && std::isfinite(p.y)) {
      pieces.back().push_back(p);
    } else if (split && !pieces.back().empty()) {
      pieces.emplace_back();
    }
  }
  if (pieces.back().empty()) pieces.pop_back();
  return pieces;
}

std::string line_path(const std::vector<Polyline>& pieces, const Box& bounds) {
  std::string d;
  for (const Polyline& piece : pieces) {
    for (const Polyline& part : clip(piece, bounds)) {
      d += "M";
      for (std::size_t k = 0; k < part.size(); ++k) {
        if (k > 0) d += " ";
        append_point(d, part[k]);
      }
      if (part.size() == 1) d += "h0";
    }
  }
  return d;
}

std::string dot_path(const std::vector<Polyline>& pieces, const Box& bounds) {
  std::string d;
  for (const Polyline& piece : pieces) {
    for (const Point& p : piece) {
      if (svg::inside(p, bounds)) d += svg::dot(p);
    }
  }
  return d;
}

Polyline clip_polygon(const Polyline& polygon, const Box& box) {
  // Sutherland–Hodgman: cut by each of the four half-planes in turn.
  Polyline out = polygon;
  const auto cut = [&out](auto keep, auto meet) {
    Polyline in;
    in.swap(out);
    for (std::size_t k = 0; k < in.size(); ++k) {
      const Point& a = in[k];
      const Point& b = in[(k + 1) % in.size()];
      if (keep(a)) out.push_back(a);
      if (keep(a) != keep(b)) out.push_back(meet(a, b));
    }
  };
  const auto at_x = [](const Point& a, const Point& b, double x) {
    return Point{x, a.y + (b.y - a.y) * (x - a.x) / (b.x - a.x)};
  };
  const auto at_y = [](const Point& a, const Point& b, double y) {
    return Point{a.x + (b.x - a.x) * (y - a.y) / (b.y - a.y), y};
  };
  cut([&](const Point& p) { return p.x >= box.left; },
      [&](const Point& a, const Point& b) { return at_x(a, b, box.left); });
  cut([&](const Point& p) { return p.x <= box.right; },
      [&](const Point& a, const Point& b) { return at_x(a, b, box.right); });
  cut([&](const Point& p) { return p.y >= box.top; },
      [&](const Point& a, const Point& b) { return at_y(a, b, box.top); });
  cut([&](const Point& p) { return p.y <= box.bottom; },
      [&](const Point& a, const Point& b) { return at_y(a, b, box.bottom); });
  return out;
}

std::string band_path(const std::vector<double>& x, const std::vector<double>& low,
                      const std::vector<double>& high, const Scale& sx, const Scale& sy,
                      const Box& bounds) {
  Polyline upper, lower;
  for (std::size_t k = 0; k < x.size(); ++k) {
    const Point a{sx(x[k]), sy(high[k])}, b{sx(x[k]), sy(low[k])};
    if (!(std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(b.y))) continue;
    upper.push_back(a);
    lower.push_back(b);
  }
  if (upper.size() < 2) return {};
  upper.insert(upper.end(), lower.rbegin(), lower.rend());
  const Polyline polygon = clip_polygon(upper, bounds);
  if (polygon.size() < 3) return {};
  std::string d = "M";
  for (std::size_t k = 0; k < polygon.size(); ++k) {
    if (k > 0) d += " ";
    append_point(d, polygon[k]);
  }
  return d + "Z";
}

namespace {

// The distance from p to the segment from a to b.
double distance_to_segment(const Point& p, const Point& a, const Point& b) {
  const double dx = b.x - a.x, dy = b.y - a.y, length2 = dx * dx + dy * dy;
  const double t =
      length2 > 0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / length2, 0.0, 1.0) : 0.0;
  return std::hypot(p.x - (a.x + t * dx), p.y - (a.y + t * dy));
}

// Whether `lines` reach more than `near` pixels from their first point: a curve, not a point
// (or a few points on one spot).
bool spans(const std::vector<Polyline>& lines, double near) {
  const Point* first = nullptr;
  for (const Polyline& part : lines) {
    for (const Point& p : part) {
      if (first == nullptr) first = &p;
      if (std::hypot(p.x - first->x, p.y - first->y) > near) return true;
    }
  }
  return false;
}

// True when every point of `hidden` lies within 1.5 pixels of the lines of `over`: drawn over it,
// `over` (about 2 pixels wide) would hide it. Both must be curves (spans): a single point is not
// a curve that another coincides with, nor one that coincides with a curve (it keeps its marker).
// Each point is first tried against the segments near the one the point before lay on, so that
// two series along each other take linear time.
bool covers(const std::vector<Polyline>& over, const std::vector<Polyline>& hidden) {
  constexpr double kNear = 1.5;
  if (!spans(over, kNear) || !spans(hidden, kNear)) return false;
  const auto near_segment = [&](const Point& p, std::size_t piece, std::size_t i) {
    const Polyline& line = over[piece];
    return distance_to_segment(p, line[i], line[i + 1 < line.size() ? i + 1 : i]) <= kNear;
  };
  bool any = false;
  std::size_t piece = 0, segment = 0;  // where the point before lay
  for (const Polyline& part : hidden) {
    for (const Point& p : part) {
      any = true;
      bool found = false;
      const auto try_segment = [&](std::size_t k, std::size_t i) {
        found = near_segment(p, k, i);
        if (found) {
          piece = k;
          segment = i;
        }
      };
      if (piece < over.size()) {
        const std::size_t end = std::min(segment + 3, over[piece].size());
        for (std::size_t i = segment > 2 ? segment - 2 : 0; i < end && !found; ++i) {
          try_segment(piece, i);
        }
      }
      for (std::size_t k = 0; k < over.size() && !found; ++k) {
        for (std::size_t i = 0; i < over[k].size() && !found; ++i) try_segment(k, i);
      }
      if (!found) return false;
    }
  }
  return any;
}

}  // namespace

std::vector<std::size_t> retraced(const std::vector<Polyline>& pieces,
                                  const std::vector<std::vector<Polyline>>& earlier,
                                  const Box& bounds) {
  const auto visible = [&](const std::vector<Polyline>& lines) {
    std::vector<Polyline> parts;
    for (const Polyline& line : lines) {
      for (Polyline& part : clip(line, bounds)) parts.push_back(std::move(part));
    }
    return parts;
  };
  const std::vector<Polyline> over = visible(pieces);
  std::vector<std::size_t> out;
  for (std::size_t k = 0; k < earlier.size(); ++k) {
    if (covers(over, visible(earlier[k]))) out.push_back(k);
  }
  return out;
}

int free_dash_pattern(const std::vector<int>& taken) {
  int k = 0;
  while (k < kDashPatterns && std::find(taken.begin(), taken.end(), k) != taken.end()) ++k;
  return k % kDashPatterns;
}

std::string dash_pattern(int k) {
  static const std::array<const char*, kDashPatterns> patterns = {
      "6 4", "2 3", "9 3 2 3", "1 4", "12 4", "4 2 1 2", "8 2", "3 6"};
  return patterns[static_cast<std::size_t>(k) % patterns.size()];
}

}  // namespace physgrad::plot
