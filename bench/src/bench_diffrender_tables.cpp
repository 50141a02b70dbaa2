// `bench diffrender`'s tables (nestlight/bench/bench_diffrender.h): which configurations each
// needs, and the tables as markdown (printed and in bench_diffrender.md), CSV and JSON.
#include <tbb/info.h>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "bench_diffrender_internal.h"
#include "nestlight/bench/harness.h"
#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/tone_map.h"
#include "nestlight/octree/error.h"

namespace nestlight::bench::drbench {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// A column: its heading in the markdown, its key in the CSV and JSON, the decimals of its numbers
// in the markdown, and whether the markdown shows it (the CSV and JSON hold every column).
struct Column {
  std::string title, key;
  int digits = 4;
  bool markdown = true;
};

struct Table {
  std::string id, title, note;
  std::vector<Column> columns;
  std::vector<std::vector<json>> rows;  // one value a column: number, string, bool or null
};

json presetOverrides(const std::string& query, const std::string& preset) {
  return {{"query", query}, {"quality", preset}};
}

json sweepOverrides(const std::string& query, int n, int cache, bool selfShadow) {
  return {{"query", query},
          {"quality", "med"},
          {"samples", n},
          {"cache", cache},
          {"self_shadow", selfShadow}};
}

bool wants(const BenchDiffrenderOptions& o, const std::string& table) {
  return std::find(o.tables.begin(), o.tables.end(), table) != o.tables.end();
}

bool hasQuery(const BenchDiffrenderOptions& o, const std::string& q) {
  return std::find(o.queries.begin(), o.queries.end(), q) != o.queries.end();
}

std::string sweepLabel(const std::string& query, int n, int cache, bool selfShadow) {
  return query + " N=" + std::to_string(n) + " cache=" + std::to_string(cache) +
         (selfShadow ? "" : " no-self-shadow");
}

// The cache of the convergence sweep at N: the option's, shrunk to N.
int sweepCacheAt(const BenchDiffrenderOptions& o, int n) {
  return std::min(o.sweepCache, n);
}

std::string cell(const json& v, int digits) {
  if (v.is_null()) return "—";
  if (v.is_string()) return v.get<std::string>();
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_number_integer()) return std::to_string(v.get<long long>());
  const double d = v.get<double>();
  if (!std::isfinite(d)) return d > 0 ? "inf" : (d < 0 ? "-inf" : "nan");
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", digits, d);
  return buf;
}

std::string csvCell(const json& v) {
  if (v.is_null()) return "";
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_float()) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "%.6g", v.get<double>());
    return buf;
  }
  const std::string text = v.is_string() ? v.get<std::string>() : v.dump();
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string q = "\"";
  for (char c : text) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string markdown(const Table& t) {
  std::string s = "### " + t.title + "\n\n" + (t.note.empty() ? "" : t.note + "\n\n");
  std::string head = "|", rule = "|";
  for (const Column& c : t.columns) {
    if (!c.markdown) continue;
    head += " " + c.title + " |";
    rule += c.digits < 0 ? "---|" : "---:|";
  }
  s += head + "\n" + rule + "\n";
  for (const auto& row : t.rows) {
    s += "|";
    for (size_t i = 0; i < t.columns.size(); ++i)
      if (t.columns[i].markdown) s += " " + cell(row[i], t.columns[i].digits) + " |";
    s += "\n";
  }
  return s + "\n";
}

void writeCsv(const Table& t, const fs::path& dir) {
  std::ofstream f(dir / ("bench_diffrender_" + t.id + ".csv"));
  for (size_t i = 0; i < t.columns.size(); ++i) f << (i ? "," : "") << t.columns[i].key;
  f << "\n";
  for (const auto& row : t.rows) {
    for (size_t i = 0; i < row.size(); ++i) f << (i ? "," : "") << csvCell(row[i]);
    f << "\n";
  }
}

json tableJson(const Table& t) {
  json rows = json::array();
  for (const auto& row : t.rows) {
    json r = json::object();
    for (size_t i = 0; i < row.size(); ++i) r[t.columns[i].key] = row[i];
    rows.push_back(r);
  }
  return {{"title", t.title}, {"note", t.note}, {"rows", rows}};
}

double passWall(const DiffrenderRun& r, const std::string& pass) {
  auto it = r.passWallMs.find(pass);
  return it == r.passWallMs.end() ? 0.0 : it->second;
}

json optionalPass(const DiffrenderRun& r, const std::string& pass, bool setup) {
  const auto& m = setup ? r.setupPassWallMs : r.passWallMs;
  auto it = m.find(pass);
  return it == m.end() ? json(nullptr) : json(it->second);
}

json counterJson(long long v) {
  return v < 0 ? json(nullptr) : json(v);
}

// The passes of the runs in the order they run: a pass one run has and the others lack goes
// after the pass it follows there.
std::vector<std::string> passOrder(const std::vector<DiffrenderRun>& runs) {
  std::vector<std::string> order;
  for (const DiffrenderRun& r : runs)
    for (size_t i = 0; i < r.passes.size(); ++i) {
      if (std::find(order.begin(), order.end(), r.passes[i]) != order.end()) continue;
      auto after =
          i == 0 ? order.begin() : std::find(order.begin(), order.end(), r.passes[i - 1]) + 1;
      order.insert(after, r.passes[i]);
    }
  return order;
}

// Tables 2 and 3: per query and preset, each pass's median time and the frame's.
Table presetTimes(const std::vector<DiffrenderRun>& rows) {
  Table t{"presets_times",
          "Tables 2 and 3: per-pass times by query and preset (ms, median of the timed runs)",
          "Each pass's wall time between glFinish() before and after it (the GPU timer queries' "
          "times, which on a CPU rasteriser charge compute work to a later pass, are the gpu_* "
          "columns of the CSV). diffrender_impostor and diffrender_scene_volume are built in the "
          "set-up frame and not again while the camera and the lights' cut stay: their build "
          "times are the set-up frame's. diffrender_shade is dL (with the material estimate) and "
          "the composite with the inserted meshes' own light.",
          {{"query", "query", -1},
           {"preset", "preset", -1},
           {"N", "samples", 0},
           {"cache", "cache", 0},
           {"object samples", "object_samples", 0},
           {"self-shadow", "self_shadow", -1}},
          {}};
  const std::vector<std::string> passes = passOrder(rows);
  for (const std::string& p : passes) t.columns.push_back({p, "pass_" + p + "_ms", 1});
  for (const std::string& p : passes) t.columns.push_back({p, "gpu_" + p + "_ms", 3, false});
  t.columns.push_back({"impostor build (set-up)", "impostor_build_ms", 1});
  t.columns.push_back({"scene volume build (set-up)", "scene_volume_build_ms", 1});
  t.columns.push_back({"frame", "frame_ms", 1});
  for (const DiffrenderRun& r : rows) {
    std::vector<json> v = {r.query, r.preset, r.samples, r.cache, r.objectSamples, r.selfShadow};
    for (const std::string& p : passes) v.push_back(optionalPass(r, p, false));
    for (const std::string& p : passes) {
      auto it = r.passGpuMs.find(p);
      v.push_back(it == r.passGpuMs.end() ? json(nullptr) : json(it->second));
    }
    v.push_back(optionalPass(r, "diffrender_impostor", true));
    v.push_back(optionalPass(r, "diffrender_scene_volume", true));
    v.push_back(r.medianMs);
    t.rows.push_back(v);
  }
  return t;
}

Table presetErrors(const std::vector<DiffrenderRun>& rows, const Bench& b) {
  char note[640];
  std::snprintf(note, sizeof note,
                "Relative L2 errors of one frame with the AOVs. R0 (nothing inserted) against "
                "R1: composite %.4f, object pixels %.4f, dL 1 by definition; the capture against "
                "R0 on scan pixels %.4f (a floor under every composite error). dL on whole %dx%d "
                "scan blocks against R1 - R0; rho against the scan's albedo on the same blocks. "
                "rho clamped, DIT unconverged and hidden: the method's counters (render info).",
                b.truth.r0Error, b.truth.r0ObjectError, b.truth.captureError, b.truth.scale,
                b.truth.scale);
  Table t{"presets_errors",
          "Tables 2 and 3: errors by query and preset",
          note,
          {{"query", "query", -1},
           {"preset", "preset", -1},
           {"frame ms", "frame_ms", 1},
           {"composite vs R1", "composite_l2", 4},
           {"composite 4x4 vs R1", "composite_l2_box4", 4},
           {"dL vs R1-R0", "delta_l2", 4},
           {"object vs R1", "object_l2", 4},
           {"rho vs albedo", "rho_l2", 4},
           {"rho clamped", "rho_clamped", 0},
           {"DIT unconverged", "dit_unconverged", 0},
           {"DIT hidden", "dit_hidden", 0},
           {"scan samples", "scan_samples", 0}},
          {}};
  for (const DiffrenderRun& r : rows)
    t.rows.push_back({r.query, r.preset, r.medianMs, r.compositeL2, r.compositeL2Box4, r.deltaL2,
                      r.objectL2, r.rhoL2, counterJson(r.rhoClamped), counterJson(r.ditUnconverged),
                      counterJson(r.ditHidden), counterJson(r.scanSamples)});
  return t;
}

// Table 4: DIT med, N x cache, with and without self-shadow.
Table cacheTable(Bench& b) {
  const BenchDiffrenderOptions& o = b.o;
  Table t{"cache",
          "Table 4: DIT at the med preset, samples N x cache (ms, median; errors relative L2)",
          "diffrender_shade (dL and the composite; its wall time, median) and the frame, with "
          "self-shadow (the med preset's) and without; the object error is where self-shadow "
          "shows.",
          {{"N", "samples", 0},
           {"cache", "cache", 0},
           {"shade ms", "shade_ms", 1},
           {"frame ms", "frame_ms", 1},
           {"dL vs R1-R0", "delta_l2", 4},
           {"object vs R1", "object_l2", 4},
           {"shade ms, no self-shadow", "shade_ms_no_self_shadow", 1},
           {"frame ms, no self-shadow", "frame_ms_no_self_shadow", 1},
           {"dL, no self-shadow", "delta_l2_no_self_shadow", 4},
           {"object, no self-shadow", "object_l2_no_self_shadow", 4}},
          {}};
  for (int n : o.samples)
    for (int c : o.caches) {
      if (c > n) continue;
      const DiffrenderRun with =
          b.run(sweepOverrides("dit", n, c, true), sweepLabel("dit", n, c, true));
      const DiffrenderRun without =
          b.run(sweepOverrides("dit", n, c, false), sweepLabel("dit", n, c, false));
      t.rows.push_back({n, c, passWall(with, "diffrender_shade"), with.medianMs, with.deltaL2,
                        with.objectL2, passWall(without, "diffrender_shade"), without.medianMs,
                        without.deltaL2, without.objectL2});
    }
  return t;
}

// Fig. 9: the inserted meshes' error per query, without self-shadow (low) and with it (med): the
// two presets differ in nothing else.
Table selfShadowTable(Bench& b) {
  Table t{"self_shadow",
          "Fig. 9: the inserted meshes' pixels against R1, without and with self-shadow",
          "Without: the low preset; with: med (they differ in self_shadow alone). R0's object "
          "error (nothing inserted): " +
              cell(b.truth.r0ObjectError, 4) + ".",
          {{"query", "query", -1},
           {"object, no self-shadow", "object_l2_no_self_shadow", 4},
           {"object, self-shadow", "object_l2_self_shadow", 4},
           {"shade ms, no self-shadow", "shade_ms_no_self_shadow", 1},
           {"shade ms, self-shadow", "shade_ms_self_shadow", 1},
           {"frame ms, no self-shadow", "frame_ms_no_self_shadow", 1},
           {"frame ms, self-shadow", "frame_ms_self_shadow", 1}},
          {}};
  for (const std::string& q : b.o.queries) {
    const DiffrenderRun low = b.run(presetOverrides(q, "low"), q + " low");
    const DiffrenderRun med = b.run(presetOverrides(q, "med"), q + " med");
    t.rows.push_back({q, low.objectL2, med.objectL2, passWall(low, "diffrender_shade"),
                      passWall(med, "diffrender_shade"), low.medianMs, med.medianMs});
  }
  return t;
}

// |dL| (the largest channel's magnitude as grey).
gi::HdrImage absoluteDelta(const gi::HdrImage& delta) {
  gi::HdrImage a(delta.width, delta.height);
  for (int y = 0; y < delta.height; ++y)
    for (int x = 0; x < delta.width; ++x) {
      const gi::Rgb c = delta.get(x, y);
      a.set(x, y, gi::Rgb(std::abs(c.r), std::abs(c.g), std::abs(c.b)));
    }
  return a;
}

// Fig. 10's images of one configuration: rho and |dL|, EXR and PNG, in images/.
std::string writeMaterialImages(const Bench& b, const DiffrenderRun& r) {
  const fs::path dir = b.dir / "images";
  fs::create_directories(dir);
  std::string stem;
  for (char c : r.label) stem += c == ' ' || c == '=' ? '_' : c;
  const gi::HdrImage rho = gi::readHdrImage((r.aovs / "diffrender_rho.exr").string());
  const gi::HdrImage dl =
      absoluteDelta(gi::readHdrImage((r.aovs / "diffrender_delta.exr").string()));
  gi::writeExr((dir / (stem + "_rho.exr")).string(), rho);
  gi::writeToneMappedPng((dir / (stem + "_rho.png")).string(), rho, 0.0);
  gi::writeExr((dir / (stem + "_abs_dl.exr")).string(), dl);
  // |dL| 4 stops over the composite's exposure: the shadow shows at a quarter of the light.
  gi::writeToneMappedPng((dir / (stem + "_abs_dl.png")).string(), dl, b.exposure + 2.0);
  return "images/" + stem + "_{rho,abs_dl}.{exr,png}";
}

Table materialTable(Bench& b) {
  Table t{"material",
          "Fig. 10: the material estimate on the floor against the true albedo",
          "Mean rho (mean of its channels) over " + b.floorRule + ", " +
              std::to_string(b.floorCount) + " blocks; the albedo's mean there " +
              cell(b.floorAlbedo, 4) +
              ". The target: within 5%. rho PNGs at 0 EV (linear rho through the sRGB curve), "
              "|dL| PNGs at the reference's exposure + 2 EV.",
          {{"query", "query", -1},
           {"preset", "preset", -1},
           {"floor rho", "floor_rho", 4},
           {"floor albedo", "floor_albedo", 4},
           {"relative error", "floor_rho_error", 4},
           {"within 5%", "within_5_percent", -1},
           {"rho vs albedo (L2, scan)", "rho_l2", 4},
           {"rho clamped", "rho_clamped", 0},
           {"images", "images", -1}},
          {}};
  std::vector<std::string> presets =
      wants(b.o, "presets") ? b.o.presets : std::vector<std::string>{"med"};
  for (const std::string& q : b.o.queries)
    for (const std::string& p : presets) {
      const DiffrenderRun r = b.run(presetOverrides(q, p), q + " " + p);
      t.rows.push_back({q, p, r.floorRho, r.floorAlbedo, r.floorRhoError, r.floorRhoError <= 0.05,
                        r.rhoL2, counterJson(r.rhoClamped), writeMaterialImages(b, r)});
    }
  return t;
}

// The configuration equal time is measured against: DIT med (the first query's med without
// DIT).
DiffrenderRun budgetRun(Bench& b) {
  const std::string q = hasQuery(b.o, "dit") ? "dit" : b.o.queries.front();
  return b.run(presetOverrides(q, "med"), q + " med");
}

// One query's sweep over N: its runs, in the order of --samples.
struct Sweep {
  std::string query;
  std::vector<DiffrenderRun> runs;
};

// Each query at the largest N whose median time (`time` of a run) is within `budget`, its dL error
// and whether it is below EM's at EM's pick: false where EM has a pick and the query none (it
// cannot render within the budget), null where EM has none or is not swept.
Table pickTable(const std::vector<Sweep>& sweeps, double budget, const std::string& id,
                const std::string& title, const std::string& note,
                double (*time)(const DiffrenderRun&), json& verdict) {
  Table t{id,
          title,
          note,
          {{"query", "query", -1},
           {"budget ms", "budget_ms", 1},
           {"N", "samples", 0},
           {"ms", "ms", 1},
           {"dL vs R1-R0", "delta_l2", 4},
           {"beats em", "beats_em", -1}},
          {}};
  std::map<std::string, std::optional<double>> picked;
  for (const Sweep& s : sweeps) {
    std::vector<std::pair<int, double>> sweep;
    for (const DiffrenderRun& r : s.runs) sweep.push_back({r.samples, time(r)});
    const std::optional<size_t> pick = equalTimePick(sweep, budget);
    picked[s.query] = pick ? std::optional<double>(s.runs[*pick].deltaL2) : std::nullopt;
    t.rows.push_back({s.query, budget, pick ? json(sweep[*pick].first) : json(nullptr),
                      pick ? json(sweep[*pick].second) : json(nullptr),
                      pick ? json(s.runs[*pick].deltaL2) : json(nullptr), nullptr});
  }
  auto beatsEm = [&](const std::string& q) -> json {
    const auto a = picked.find(q), e = picked.find("em");
    if (q == "em" || a == picked.end() || e == picked.end() || !e->second) return nullptr;
    return a->second && *a->second < *e->second;
  };
  for (auto& row : t.rows) row.back() = beatsEm(row[0].get<std::string>());
  verdict = {{"budget_ms", budget}};
  for (const char* q : {"dit", "vct"}) {
    verdict[std::string(q) + "_beats_em"] = beatsEm(q);
    verdict[std::string(q) + "_within_budget"] =
        picked.count(q) ? json(picked[q].has_value()) : json(nullptr);
  }
  return t;
}

double frameTime(const DiffrenderRun& r) {
  return r.medianMs;
}

double shadeTime(const DiffrenderRun& r) {
  return passWall(r, "diffrender_shade");
}

// Fig. 11: dL error over N per query (the sweep at the med preset, its cache shrunk to N), and
// at equal time: of the frame (the target's measure) and of the shade pass alone (the paper's:
// "within 10 ms of differential background computation").
std::vector<Table> equalTimeTables(Bench& b, json& verdict) {
  const BenchDiffrenderOptions& o = b.o;
  const std::vector<std::string> swept = sweepQueries(o);
  std::string notSwept;
  for (const std::string& q : o.queries)
    if (std::find(swept.begin(), swept.end(), q) == swept.end())
      notSwept += (notSwept.empty() ? "" : ", ") + q;
  Table conv{"convergence",
             "Fig. 11: dL error against N per query (med preset, cache " +
                 std::to_string(o.sweepCache) + " or N where smaller)",
             notSwept.empty() ? ""
                              : "Not swept: " + notSwept +
                                    " (--sweep-queries; by default exact is left out, its frames "
                                    "taking seconds on a CPU rasteriser).",
             {{"query", "query", -1},
              {"N", "samples", 0},
              {"cache", "cache", 0},
              {"frame ms", "frame_ms", 1},
              {"shade ms", "shade_ms", 1},
              {"dL vs R1-R0", "delta_l2", 4},
              {"object vs R1", "object_l2", 4}},
             {}};
  const DiffrenderRun base = budgetRun(b);
  std::vector<Sweep> sweeps;
  for (const std::string& q : swept) {
    sweeps.push_back({q, {}});
    for (int n : o.samples) {
      const int c = sweepCacheAt(o, n);
      const DiffrenderRun r = b.run(sweepOverrides(q, n, c, true), sweepLabel(q, n, c, true));
      sweeps.back().runs.push_back(r);
      conv.rows.push_back({q, n, c, r.medianMs, shadeTime(r), r.deltaL2, r.objectL2});
    }
  }
  const double frameBudget = o.equalTimeMs ? *o.equalTimeMs : base.medianMs;
  const std::string frameHow = o.equalTimeMs ? "--equal-time-ms" : base.label + "'s median frame";
  json byFrame, byShade;
  Table eq = pickTable(sweeps, frameBudget, "equal_time", "Fig. 11: dL error at equal frame time",
                       "Budget " + cell(frameBudget, 1) + " ms (" + frameHow +
                           "); each query at the largest N of the sweep whose median frame time "
                           "is within it. beats em: its dL error below EM's at EM's pick (no "
                           "where it has no N within the budget).",
                       frameTime, byFrame);
  Table eqShade = pickTable(
      sweeps, shadeTime(base), "equal_time_shade",
      "Fig. 11: dL error at equal time of the shade pass",
      "Budget " + cell(shadeTime(base), 1) + " ms, " + base.label +
          "'s diffrender_shade (dL and the composite): the paper's measure, the differential "
          "background's time alone, without the passes every query shares.",
      shadeTime, byShade);
  byFrame["budget_from"] = frameHow;
  byShade["budget_from"] = base.label + "'s diffrender_shade";
  verdict = byFrame;
  verdict["by_shade_pass"] = byShade;
  return {conv, eq, eqShade};
}

json runJson(const DiffrenderRun& r) {
  json passes = json::object();
  for (const std::string& p : r.passes)
    passes[p] = {{"gpu_ms", r.passGpuMs.at(p)}, {"wall_ms", r.passWallMs.at(p)}};
  json setup = json::object();
  for (const auto& [p, ms] : r.setupPassWallMs) setup[p] = ms;
  return {{"label", r.label},
          {"overrides", r.overrides},
          {"query", r.query},
          {"preset", r.preset},
          {"samples", r.samples},
          {"cache", r.cache},
          {"object_samples", r.objectSamples},
          {"self_shadow", r.selfShadow},
          {"secondary_bounce", r.secondaryBounce},
          {"setup_ms", r.setupMs},
          {"frame_ms_runs", r.frameMs},
          {"frame_ms", r.medianMs},
          {"passes_ms", passes},
          {"setup_passes_wall_ms", setup},
          {"composite_l2", r.compositeL2},
          {"composite_l2_box4", r.compositeL2Box4},
          {"delta_l2", r.deltaL2},
          {"object_l2", r.objectL2},
          {"rho_l2", r.rhoL2},
          {"floor_rho", r.floorRho},
          {"floor_albedo", r.floorAlbedo},
          {"floor_rho_error", r.floorRhoError},
          {"rho_clamped", counterJson(r.rhoClamped)},
          {"dit_unconverged", counterJson(r.ditUnconverged)},
          {"dit_hidden", counterJson(r.ditHidden)},
          {"scan_samples", counterJson(r.scanSamples)},
          {"aovs", r.aovs.string()}};
}

// One CSV row per configuration measured: every number of runJson, the passes flattened.
void writeRunsCsv(const Bench& b) {
  const std::vector<std::string> passes = passOrder(b.runs);
  std::ofstream f(b.dir / "bench_diffrender_runs.csv");
  const std::vector<std::string> keys = {
      "label",        "query",           "preset",       "samples",
      "cache",        "object_samples",  "self_shadow",  "secondary_bounce",
      "setup_ms",     "frame_ms",        "composite_l2", "composite_l2_box4",
      "delta_l2",     "object_l2",       "rho_l2",       "floor_rho",
      "floor_albedo", "floor_rho_error", "rho_clamped",  "dit_unconverged",
      "dit_hidden",   "scan_samples"};
  for (size_t i = 0; i < keys.size(); ++i) f << (i ? "," : "") << keys[i];
  for (const std::string& p : passes) f << ",wall_" << p << "_ms,gpu_" << p << "_ms";
  f << "\n";
  for (const DiffrenderRun& r : b.runs) {
    const json j = runJson(r);
    for (size_t i = 0; i < keys.size(); ++i) f << (i ? "," : "") << csvCell(j[keys[i]]);
    for (const std::string& p : passes) {
      const bool has = r.passWallMs.count(p) > 0;
      f << "," << (has ? csvCell(r.passWallMs.at(p)) : "") << ","
        << (has ? csvCell(r.passGpuMs.at(p)) : "");
    }
    f << "\n";
  }
}

// A reference's sample count as its info holds it (a number, or a string when read back from the
// cache).
std::string samplesOf(const json& info) {
  const json s = info.value("samples", json("?"));
  return s.is_string() ? s.get<std::string>() : s.dump();
}

std::string header(const Bench& b, const std::string& device) {
  char text[1024];
  std::snprintf(
      text, sizeof text,
      "## bench diffrender: %s\n\n%dx%d; device: %s; median of %d timed runs after a "
      "set-up frame (making the method and one untimed frame), errors from one more frame "
      "with the AOVs. R1 and R0: the path-traced reference with and without the inserted "
      "meshes to %.4g estimated error (%s and %s spp).\n\n",
      b.sceneFile.string().c_str(), b.W, b.H, device.c_str(), b.o.runs, b.o.referenceError,
      samplesOf(b.truth.info["r1"]).c_str(), samplesOf(b.truth.info["r0"]).c_str());
  return text;
}

std::string verdictText(const json& v) {
  auto one = [](const json& w, const char* q) {
    const json& x = w[std::string(q) + "_beats_em"];
    if (x.is_null()) return std::string(q) + ": not measured";
    if (x.get<bool>()) return std::string(q) + ": yes";
    return std::string(q) + (w[std::string(q) + "_within_budget"] == false
                                 ? ": no (no N within the budget)"
                                 : ": no");
  };
  return "Target \"DIT and VCT beat EM in dL error at equal time\" (frame time): " + one(v, "dit") +
         "; " + one(v, "vct") + ". By the shade pass's time: " + one(v["by_shade_pass"], "dit") +
         "; " + one(v["by_shade_pass"], "vct") + ".\n\n";
}

}  // namespace

const std::vector<std::string>& tableNames() {
  static const std::vector<std::string> names = {"presets", "cache", "self-shadow", "material",
                                                 "equal-time"};
  return names;
}

std::vector<json> plannedOverrides(const BenchDiffrenderOptions& o) {
  std::vector<json> v;
  // low and med: Fig. 9's pair and the equal-time budget's configuration.
  std::vector<std::string> presets = {"low", "med"};
  presets.insert(presets.end(), o.presets.begin(), o.presets.end());
  for (const std::string& q : o.queries)
    for (const std::string& p : presets) v.push_back(presetOverrides(q, p));
  for (int n : o.samples) {
    for (int c : o.caches)
      if (c <= n)
        for (bool selfShadow : {true, false}) v.push_back(sweepOverrides("dit", n, c, selfShadow));
    for (const std::string& q : sweepQueries(o))
      v.push_back(sweepOverrides(q, n, sweepCacheAt(o, n), true));
  }
  return v;
}

BenchDiffrenderReport makeTables(Bench& b) {
  const BenchDiffrenderOptions& o = b.o;
  std::vector<Table> tables;
  json verdict = nullptr;
  if (wants(o, "presets")) {
    std::vector<DiffrenderRun> rows;
    for (const std::string& q : o.queries)
      for (const std::string& p : o.presets)
        rows.push_back(b.run(presetOverrides(q, p), q + " " + p));
    tables.push_back(presetTimes(rows));
    tables.push_back(presetErrors(rows, b));
  }
  if (wants(o, "cache") && hasQuery(o, "dit")) tables.push_back(cacheTable(b));
  if (wants(o, "self-shadow")) tables.push_back(selfShadowTable(b));
  if (wants(o, "material")) tables.push_back(materialTable(b));
  if (wants(o, "equal-time"))
    for (Table& t : equalTimeTables(b, verdict)) tables.push_back(std::move(t));
  const std::string device = (o.device.empty() ? std::string("unknown CPU") : o.device) + ", " +
                             std::to_string(tbb::info::default_concurrency()) +
                             " threads; GL: " + b.glDevice;
  BenchDiffrenderReport report;
  report.dir = b.dir;
  report.markdown = header(b, device);
  if (wants(o, "cache") && !hasQuery(o, "dit"))
    report.markdown += "Table 4 (cache) is DIT's: not measured without dit in --queries.\n\n";
  json jt = json::object();
  for (const Table& t : tables) {
    report.markdown += markdown(t);
    if (t.id == "equal_time_shade") report.markdown += verdictText(verdict);
    writeCsv(t, b.dir);
    jt[t.id] = tableJson(t);
  }
  writeRunsCsv(b);
  json runs = json::array();
  for (const DiffrenderRun& r : b.runs) runs.push_back(runJson(r));
  report.json = {
      {"scene", b.sceneFile.string()},
      {"device", device},
      {"width", b.W},
      {"height", b.H},
      {"runs", o.runs},
      {"truth", b.truth.info},
      {"floor", {{"rule", b.floorRule}, {"blocks", b.floorCount}, {"albedo", b.floorAlbedo}}},
      {"equal_time", verdict},
      {"tables", jt},
      {"configurations", runs}};
  report.runs = b.runs;
  std::ofstream(b.dir / "bench_diffrender.json") << report.json.dump(2) << "\n";
  std::ofstream(b.dir / "bench_diffrender.md") << report.markdown;
  say(b.log, "\n%s", report.markdown.c_str());
  say(b.log, "bench diffrender: wrote %s/bench_diffrender.{md,json} and bench_diffrender_*.csv\n",
      b.dir.c_str());
  return report;
}

}  // namespace nestlight::bench::drbench
