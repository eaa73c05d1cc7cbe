// foveal/impair/field.cpp — perimetry files, standard grids, generators, interpolation, the loss map.
#include "foveal/impair/field.h"

#include "foveal/util/text.h"
#include "foveal/util/error.h"
#include "foveal/util/units.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <sstream>

namespace foveal {

const char* to_string(Eye eye) { return eye == Eye::od ? "OD" : "OS"; }

std::optional<Eye> parse_eye_side(std::string_view text) {
  std::string s(text);
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (s == "OD") return Eye::od;
  if (s == "OS") return Eye::os;
  return std::nullopt;
}

const char* to_string(FieldValue kind) {
  switch (kind) {
    case FieldValue::sensitivity_db:
      return "sensitivity_db";
    case FieldValue::total_deviation_db:
      return "total_deviation_db";
    case FieldValue::pattern_deviation_db:
      return "pattern_deviation_db";
  }
  return "?";
}

std::vector<glm::dvec2> standard_grid(const std::string& name, Eye eye) {
  // Test locations on a square lattice offset from both meridians: 6° spacing for 24-2 and 30-2,
  // 2° for 10-2, within each grid's radius; the 24-2 adds two nasal locations at 27° (x < 0 in OD).
  double spacing = 6, max_r2 = 0;
  if (name == "24-2")
    max_r2 = 522;  // 9² + 21²
  else if (name == "30-2")
    max_r2 = 810;  // 9² + 27²
  else if (name == "10-2")
    spacing = 2, max_r2 = 82;  // 1² + 9²
  else
    fail("unknown perimetry grid '{}' (expected 24-2, 30-2 or 10-2)", name);
  std::vector<glm::dvec2> grid;
  const int half = static_cast<int>(std::sqrt(max_r2) / spacing) + 2;  // reaches the 24-2 nasal step at 27°
  for (int j = half - 1; j >= -half; --j)
    for (int i = -half; i < half; ++i) {
      const double x = (i + 0.5) * spacing, y = (j + 0.5) * spacing;
      const bool nasal_step = name == "24-2" && std::abs(y) == 3 && x == (eye == Eye::od ? -27 : 27);
      if (x * x + y * y <= max_r2 || nasal_step) grid.emplace_back(x, y);
    }
  return grid;  // rows from the top, left to right: the reading order
}

bool is_blind_spot_location(const std::string& grid, Eye eye, glm::dvec2 p) {
  if (grid != "24-2" && grid != "30-2") return false;
  return p.x == (eye == Eye::od ? 15 : -15) && std::abs(p.y) == 3;
}

glm::dvec2 blind_spot_centre(Eye eye) { return {eye == Eye::od ? kBlindSpotXDeg : -kBlindSpotXDeg, kBlindSpotYDeg}; }

double blind_spot_loss_db(Eye eye, glm::dvec2 p) {
  const glm::dvec2 c = blind_spot_centre(eye);
  // distance outside the ellipse, approximately in degrees (the radial scale times the ellipse's mean radius)
  const double r = std::hypot((p.x - c.x) / (kBlindSpotWidthDeg / 2), (p.y - c.y) / (kBlindSpotHeightDeg / 2));
  const double outside_deg = (r - 1.0) * 0.25 * (kBlindSpotWidthDeg + kBlindSpotHeightDeg);
  return kAbsoluteLossDb * std::clamp(0.5 - outside_deg / 0.5, 0.0, 1.0);
}

namespace {

bool inside_blind_spot(Eye eye, glm::dvec2 p) {
  const glm::dvec2 c = blind_spot_centre(eye);
  return std::hypot((p.x - c.x) / (kBlindSpotWidthDeg / 2), (p.y - c.y) / (kBlindSpotHeightDeg / 2)) < 1.0;
}

struct Header {
  int x = -1, y = -1, value = -1, eye = -1;
  FieldValue kind = FieldValue::total_deviation_db;
};

// Plausible dB ranges: sensitivities of standard automated perimetry, deviations from normal
void check_range(const std::string& where, FieldValue kind, double v) {
  const bool ok = kind == FieldValue::sensitivity_db ? v >= -10 && v <= 50 : v >= -50 && v <= 30;
  if (!ok)
    fail("{}: {} value {} is out of range ({})", where, to_string(kind), v,
         kind == FieldValue::sensitivity_db ? "-10 to 50 dB" : "-50 to 30 dB");
}

}  // namespace

std::vector<PerimetryField> parse_field_csv(const std::string& raw, const std::string& name, const std::string& grid, Eye default_eye,
                                            double age, const NormalModel& normal) {
  const std::string_view text = text::strip_bom(raw);
  text::Lines lines(text);
  std::string_view line;
  Header h;
  int columns = 0;
  // The header: the first line that is not empty
  while (lines.next(line) && text::trim(line).empty()) {}
  if (text::trim(line).empty()) fail("{}: empty field file (expected a header such as x_deg,y_deg,total_deviation_db)", name);
  const int header_line = lines.number();
  {
    const auto fields = text::split(line, ',');
    columns = static_cast<int>(fields.size());
    for (int i = 0; i < columns; ++i) {
      std::string f(text::trim(fields[i]));
      if (f.size() >= 2 && f.front() == '"' && f.back() == '"') f = f.substr(1, f.size() - 2);
      auto set = [&](int& column) {
        if (column >= 0) fail("{}:{}: column '{}' appears twice", name, header_line, f);
        column = i;
      };
      if (f == "x_deg")
        set(h.x);
      else if (f == "y_deg")
        set(h.y);
      else if (f == "eye")
        set(h.eye);
      else if (f == "sensitivity_db" || f == "total_deviation_db" || f == "pattern_deviation_db") {
        set(h.value);
        h.kind = f == "sensitivity_db"       ? FieldValue::sensitivity_db
                 : f == "total_deviation_db" ? FieldValue::total_deviation_db
                                             : FieldValue::pattern_deviation_db;
      } else {
        fail(
            "{}:{}: unknown column '{}' (expected x_deg, y_deg, eye and one of sensitivity_db, total_deviation_db, "
            "pattern_deviation_db)",
            name, header_line, f);
      }
    }
  }
  if (h.value < 0) fail("{}:{}: no value column (sensitivity_db, total_deviation_db or pattern_deviation_db)", name, header_line);
  const bool located = h.x >= 0 || h.y >= 0;
  if (located && (h.x < 0 || h.y < 0)) fail("{}:{}: x_deg and y_deg go together", name, header_line);
  if (located && !grid.empty()) fail("{}: the file has x_deg,y_deg: do not also name a grid ('{}')", name, grid);
  if (!located && grid.empty())
    fail("{}:{}: no x_deg,y_deg columns: name the grid the values follow (e.g. field:24-2:{})", name, header_line, name);

  std::map<Eye, PerimetryField> eyes;
  std::map<Eye, std::vector<int>> value_lines;
  while (lines.next(line)) {
    if (text::trim(line).empty()) continue;
    const std::string where = fmt::format("{}:{}", name, lines.number());
    const auto fields = text::split(line, ',');
    if (static_cast<int>(fields.size()) != columns) fail("{}: {} fields, the header has {}", where, fields.size(), columns);
    auto number = [&](int column, const char* what) {
      const auto v = text::to_number(text::trim(fields[column]));
      if (!v) fail("{}: {} '{}' is not a number", where, what, text::trim(fields[column]));
      return *v;
    };
    Eye eye = default_eye;
    if (h.eye >= 0) {
      const auto e = parse_eye_side(text::trim(fields[h.eye]));
      if (!e) fail("{}: eye '{}' is neither OD nor OS", where, text::trim(fields[h.eye]));
      eye = *e;
    }
    PerimetryField& f = eyes[eye];
    f.eye = eye;
    f.kind = h.kind;
    FieldPoint p;
    p.value_db = number(h.value, to_string(h.kind));
    check_range(where, h.kind, p.value_db);
    if (located) {
      p.x_deg = number(h.x, "x_deg");
      p.y_deg = number(h.y, "y_deg");
      if (std::abs(p.x_deg) > 90 || std::abs(p.y_deg) > 90) fail("{}: location ({}, {}) is beyond 90°", where, p.x_deg, p.y_deg);
      for (const FieldPoint& q : f.points)
        if (q.x_deg == p.x_deg && q.y_deg == p.y_deg)
          fail("{}: location ({}, {}) of {} appears twice", where, p.x_deg, p.y_deg, to_string(eye));
    }
    f.points.push_back(p);
    value_lines[eye].push_back(lines.number());
  }
  if (eyes.empty()) fail("{}: no values after the header", name);
  std::vector<PerimetryField> out;
  for (auto& [eye, f] : eyes) {
    if (!located) {
      const std::vector<glm::dvec2> locations = standard_grid(grid, eye);
      if (f.points.size() != locations.size())
        fail("{}: {} values for {}, the {} grid has {} locations", name, f.points.size(), to_string(eye), grid, locations.size());
      std::vector<FieldPoint> kept;
      for (size_t i = 0; i < locations.size(); ++i) {
        f.points[i].x_deg = locations[i].x;
        f.points[i].y_deg = locations[i].y;
        if (!is_blind_spot_location(grid, eye, locations[i])) kept.push_back(f.points[i]);
      }
      f.points = kept;  // the blind spot's own test locations are not part of the loss
    }
    for (FieldPoint& p : f.points) {
      const double normal_db = normal.sensitivity_db(age, std::hypot(p.x_deg, p.y_deg));
      p.loss_db = std::max(0.0, f.kind == FieldValue::sensitivity_db ? normal_db - p.value_db : -p.value_db);
    }
    out.push_back(std::move(f));
  }
  return out;
}

std::vector<PerimetryField> read_field_file(const std::string& path, const std::string& grid, Eye default_eye, double age,
                                            const NormalModel& normal) {
  return parse_field_csv(text::read_file(path), path, grid, default_eye, age, normal);
}

double interpolate_loss_db(const PerimetryField& field, double x, double y) {
  const bool upper = y >= 0;
  // Shepard's 1/d² weights tapered by a Gaussian of the grid's spacing: exact at the locations,
  // continuous everywhere (every location of the hemifield takes part), local, and the nearest
  // locations' values far beyond the grid. Weights relative to the nearest one (no underflow).
  constexpr double kSigmaDeg = 6.0;
  double nearest = INFINITY;
  for (const FieldPoint& p : field.points) {
    if ((p.y_deg >= 0) != upper || inside_blind_spot(field.eye, {p.x_deg, p.y_deg})) continue;
    const double d2 = (p.x_deg - x) * (p.x_deg - x) + (p.y_deg - y) * (p.y_deg - y);
    if (d2 < 1e-12) return p.loss_db;
    nearest = std::min(nearest, d2);
  }
  if (!std::isfinite(nearest)) return 0.0;  // a hemifield without locations: no loss known
  double sum = 0, weight = 0;
  for (const FieldPoint& p : field.points) {
    if ((p.y_deg >= 0) != upper || inside_blind_spot(field.eye, {p.x_deg, p.y_deg})) continue;
    const double d2 = (p.x_deg - x) * (p.x_deg - x) + (p.y_deg - y) * (p.y_deg - y);
    const double w = std::exp(-(d2 - nearest) / (2 * kSigmaDeg * kSigmaDeg)) * nearest / d2;
    sum += w * p.loss_db;
    weight += w;
  }
  return sum / weight;
}

PerimetryField integrated_field(const PerimetryField& od, const PerimetryField& os) {
  PerimetryField ivf = od;
  for (const FieldPoint& p : os.points) {
    auto same =
        std::find_if(ivf.points.begin(), ivf.points.end(), [&](const FieldPoint& q) { return q.x_deg == p.x_deg && q.y_deg == p.y_deg; });
    if (same == ivf.points.end())
      ivf.points.push_back(p);
    else if (p.loss_db < same->loss_db)
      *same = p;
  }
  return ivf;
}

FieldMap::FieldMap() : n_(static_cast<int>(std::lround(2 * kExtentDeg / kStepDeg))), loss_(size_t(n_) * n_, 0.0f) {}

FieldMap FieldMap::from_function(const std::function<double(double, double)>& loss_db) {
  FieldMap m;
  for (int j = 0; j < m.n_; ++j)
    for (int i = 0; i < m.n_; ++i) {
      const double x = -kExtentDeg + (i + 0.5) * kStepDeg, y = kExtentDeg - (j + 0.5) * kStepDeg;
      const float v = static_cast<float>(std::max(0.0, loss_db(x, y)));
      m.loss_[size_t(j) * m.n_ + i] = v;
      m.max_loss_ = std::max(m.max_loss_, double(v));
    }
  return m;
}

FieldMap FieldMap::best_of(const FieldMap& a, const FieldMap& b) {
  FieldMap m;
  for (size_t i = 0; i < m.loss_.size(); ++i) {
    m.loss_[i] = std::min(a.loss_[i], b.loss_[i]);
    m.max_loss_ = std::max(m.max_loss_, double(m.loss_[i]));
  }
  return m;
}

namespace {

double smooth_step(double edge0, double edge1, double v) {
  const double t = std::clamp((v - edge0) / (edge1 - edge0), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

}  // namespace

std::function<double(double, double)> generated_defect(const std::string& spec, Eye eye) {
  std::vector<std::string> parts;
  {
    std::stringstream s(spec);
    for (std::string p; std::getline(s, p, ':');) parts.push_back(p);
  }
  if (parts.empty()) fail("field: empty defect");
  const std::string kind = parts[0];
  auto number = [&](size_t i, double fallback, const char* what) {
    if (i >= parts.size() || parts[i].empty()) return fallback;
    const auto v = text::to_number(parts[i]);
    if (!v) fail("field:{}: {} '{}' is not a number", spec, what, parts[i]);
    return *v;
  };
  auto side = [&](size_t i, const std::string& fallback, std::initializer_list<const char*> allowed) {
    const std::string v = i < parts.size() ? parts[i] : fallback;
    for (const char* a : allowed)
      if (v == a) return v;
    fail("field:{}: '{}' is not one of the allowed sides", spec, v);
  };
  auto depth_at = [&](size_t i) {
    const double d = number(i, 25.0, "depth");
    if (!(d > 0 && d <= kAbsoluteLossDb)) fail("field:{}: depth must be in (0, {}] dB, got {}", spec, kAbsoluteLossDb, d);
    return d;
  };
  auto radius_at = [&](size_t i) {
    if (i >= parts.size()) fail("field:{}: needs a radius in degrees (e.g. field:{}:10)", spec, kind);
    const double r = number(i, 0, "radius");
    if (!(r > 0 && r <= 90)) fail("field:{}: radius must be in (0, 90] degrees, got {}", spec, r);
    return r;
  };
  auto no_more = [&](size_t count) {
    if (parts.size() > count) fail("field:{}: too many values", spec);
  };
  // eye-relative defects are described for OD (nasal = x < 0) and mirrored for OS
  const double nasal_sign = eye == Eye::od ? -1.0 : 1.0;
  if (kind == "arcuate" || kind == "nasal-step" || kind == "paracentral" || kind == "altitudinal") {
    const double depth = depth_at(1);
    const double up = side(2, "superior", {"superior", "inferior"}) == "superior" ? 1.0 : -1.0;
    no_more(3);
    if (kind == "arcuate")
      return [=](double x, double y) {
        if (y * up < 0) return 0.0;
        const double r = std::hypot(x, y);
        // the angle from the temporal meridian (the blind spot's side) round to the nasal one, 0–180°
        const double a = std::atan2(std::abs(y), x * -nasal_sign) * kDeg;
        return depth * smooth_step(9, 11, r) * (1 - smooth_step(19, 21, r)) * smooth_step(10, 25, a);
      };
    if (kind == "nasal-step") return [=](double x, double y) { return y * up < 0 ? 0.0 : depth * smooth_step(12, 18, x * nasal_sign); };
    if (kind == "paracentral")
      return [=](double x, double y) {
        if (y * up < 0) return 0.0;
        return depth * (1 - smooth_step(2.5, 3.5, std::hypot(x - 5 * nasal_sign, y - 5 * up)));
      };
    return [=](double, double y) { return y * up < 0 ? 0.0 : depth; };
  }
  if (kind == "constriction" || kind == "central") {
    const double r = radius_at(1), depth = depth_at(2);
    no_more(3);
    if (kind == "constriction") return [=](double x, double y) { return depth * smooth_step(r - 1, r + 1, std::hypot(x, y)); };
    return [=](double x, double y) { return depth * (1 - smooth_step(r - 0.5, r + 0.5, std::hypot(x, y))); };
  }
  if (kind == "hemianopia") {
    if (parts.size() < 2) fail("field:{}: needs a side (hemianopia:left or hemianopia:right)", spec);
    const double sign = side(1, "", {"left", "right"}) == "left" ? -1.0 : 1.0;
    const double depth = depth_at(2);
    no_more(3);
    return [=](double x, double) { return depth * smooth_step(-0.25, 0.25, x * sign); };
  }
  if (kind == "quadrantanopia") {
    if (parts.size() < 2) fail("field:{}: needs a quadrant (upper-left, upper-right, lower-left, lower-right)", spec);
    const std::string q = side(1, "", {"upper-left", "upper-right", "lower-left", "lower-right"});
    const double sx = q.ends_with("left") ? -1.0 : 1.0, sy = q.starts_with("upper") ? 1.0 : -1.0;
    const double depth = depth_at(2);
    no_more(3);
    return [=](double x, double y) { return y * sy < 0 ? 0.0 : depth * smooth_step(-0.25, 0.25, x * sx); };
  }
  fail(
      "field: unknown defect '{}' (expected a .csv file, 24-2:FILE, arcuate, nasal-step, paracentral, constriction:R, "
      "central:R, altitudinal, hemianopia:left|right, quadrantanopia:QUADRANT)",
      kind);
}

std::string VisualField::resolved_view() const {
  bool has_od = false, has_os = false;
  for (const PerimetryField& f : measured) (f.eye == Eye::od ? has_od : has_os) = true;
  for (const Generated& g : generated)
    if (g.eye) (*g.eye == Eye::od ? has_od : has_os) = true;
  if (view != "auto") return view;
  return has_od && has_os ? "both" : has_os ? "OS" : "OD";
}

std::vector<FieldPoint> VisualField::view_points() const {
  const std::string v = resolved_view();
  std::optional<PerimetryField> merged;
  for (const PerimetryField& f : measured) {
    if (v != "both" && to_string(f.eye) != v) continue;
    merged = merged ? integrated_field(*merged, f) : f;
  }
  return merged ? merged->points : std::vector<FieldPoint>{};
}

FieldMap VisualField::map() const {
  if (empty()) return FieldMap();
  bool has_od = false, has_os = false;
  for (const PerimetryField& f : measured) (f.eye == Eye::od ? has_od : has_os) = true;
  const std::string v = resolved_view();
  auto eye_map = [&](Eye eye, bool with_blind_spot) {
    std::vector<std::function<double(double, double)>> parts;
    for (const PerimetryField& f : measured)
      if (f.eye == eye) parts.push_back([&f](double x, double y) { return interpolate_loss_db(f, x, y); });
    for (const Generated& g : generated)
      if (!g.eye || *g.eye == eye) parts.push_back(generated_defect(g.spec, eye));
    return FieldMap::from_function([&](double x, double y) {
      double loss = 0;
      for (const auto& p : parts) loss = std::max(loss, p(x, y));
      if (with_blind_spot) loss = std::max(loss, blind_spot_loss_db(eye, {x, y}));
      return loss;
    });
  };
  if (v == "both") {
    // each eye without its blind spot: the other eye sees there (the integrated field)
    if (!generated.empty() || (has_od && has_os)) return FieldMap::best_of(eye_map(Eye::od, false), eye_map(Eye::os, false));
    return eye_map(has_os ? Eye::os : Eye::od, false);
  }
  if (v != "OD" && v != "OS") fail("field view must be OD, OS or both, got '{}'", v);
  const Eye eye = v == "OD" ? Eye::od : Eye::os;
  if (std::any_of(generated.begin(), generated.end(), [&](const Generated& g) { return !g.eye || *g.eye == eye; }) ||
      std::any_of(measured.begin(), measured.end(), [&](const auto& f) { return f.eye == eye; }))
    return eye_map(eye, blind_spot);
  fail("field view {}: no field of that eye was given", v);
}

}  // namespace foveal
