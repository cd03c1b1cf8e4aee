#include "tools/report/comparison_html.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace photopose::cli {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The x value of a setting along `axis` and the axis label.
std::string AxisLabel(const std::string& axis) {
  if (axis == "noise") return "image noise (px, one sigma)";
  if (axis == "outliers") return "outlier fraction (%)";
  if (axis == "control") return "control points per image";
  return "initial angle error (+- deg per angle)";
}

double PlotX(const SweepSetting& setting, const std::string& axis) {
  const double value = AxisValue(setting, axis);
  return axis == "outliers" ? 100.0 * value : value;
}

// Value columns of one HTML table at most; wider tables are split into blocks (RenderHtmlTable).
constexpr size_t kMaxHtmlValueColumns = 10;

// Solvers within this fraction of the best position RMSE tie for the most accurate: with tens of
// trials the RMSE itself is uncertain by several per cent (unitless).
constexpr double kTieFraction = 0.05;

// "a, b and c" of the names at `indices`, each in <b>.
std::string NameList(const std::vector<std::string>& names, const std::vector<size_t>& indices) {
  std::string out;
  for (size_t k = 0; k < indices.size(); ++k) {
    out += (k == 0 ? "" : (k + 1 == indices.size() ? " and " : ", ")) + std::string("<b>") +
           HtmlEscape(names[indices[k]]) + "</b>";
  }
  return out.empty() ? "none" : out;
}

// The fastest of `indices` by `seconds`.
size_t Fastest(const std::vector<double>& seconds, const std::vector<size_t>& indices) {
  size_t best = indices.front();
  for (const size_t k : indices)
    if (seconds[k] < seconds[best]) best = k;
  return best;
}

// The verdict of one scenario of a Monte-Carlo run.
std::string ScenarioVerdict(const MonteCarloOptions& options, const MonteCarloResult& result,
                            Scenario scenario) {
  const SettingResult* baseline = nullptr;
  const SettingResult* most_outliers = nullptr;
  for (const SettingResult& setting : result.settings) {
    if (setting.setting.scenario != scenario) continue;
    if (baseline == nullptr) baseline = &setting;
    if (setting.setting.outlier_fraction > baseline->setting.outlier_fraction &&
        (most_outliers == nullptr ||
         setting.setting.outlier_fraction > most_outliers->setting.outlier_fraction))
      most_outliers = &setting;
  }
  std::ostringstream html;
  if (baseline == nullptr) return "";
  const std::vector<SolverStatistics>& base = baseline->solvers;
  // Accuracy among the solvers with the best success rate (within one sample).
  double best_success = 0.0;
  for (const SolverStatistics& s : base) best_success = std::max(best_success, s.success_rate);
  const double one_sample = 1.0 / std::max(1, base.empty() ? 1 : base.front().samples);
  std::vector<double> rmse, seconds;
  for (const SolverStatistics& s : base) {
    rmse.push_back(s.solved > 0 && s.success_rate >= best_success - one_sample - 1e-12
                       ? s.position_rmse_m
                       : kNaN);
    seconds.push_back(s.median_seconds);
  }
  const std::vector<size_t> tied = TiedBest(rmse, kTieFraction);
  if (tied.empty()) {
    html << "<div class=\"verdict bad\"><b>" << EnumName(scenario)
         << ":</b> no solver returned a pose at the baseline ("
         << HtmlEscape(SweepSettingTitle(baseline->setting, options.trials,
                                         baseline->images_per_trial))
         << ").</div>\n";
    return html.str();
  }
  const size_t fastest = Fastest(seconds, tied);
  html << "<div class=\"verdict good\"><b>" << EnumName(scenario) << ": use "
       << HtmlEscape(result.solver_names[fastest]) << ".</b> At the baseline ("
       << HtmlEscape(SweepSettingTitle(baseline->setting, options.trials,
                                       baseline->images_per_trial))
       << ") " << NameList(result.solver_names, tied)
       << (tied.size() > 1 ? " tie for the most accurate" : " is the most accurate")
       << " (position RMSE " << FormatLengthWithUnit(base[tied.front()].position_rmse_m);
  if (tied.size() > 1) html << " within " << FormatUnitless(100.0 * kTieFraction, 0) << " %";
  html << ", success " << FormatUnitless(100.0 * base[fastest].success_rate, 0) << " %)";
  if (tied.size() > 1)
    html << "; " << HtmlEscape(result.solver_names[fastest]) << " is the fastest of them ("
         << FormatSignificant(1e6 * base[fastest].median_seconds, 3) << " " << Utf8UnitName("us")
         << " per image)";
  html << ".";
  // Honest covariances.
  std::vector<size_t> honest, optimistic;
  for (size_t k = 0; k < base.size(); ++k) {
    if (base[k].nees_count == 0 || !std::isfinite(base[k].mean_nees_apriori)) continue;
    (base[k].nees_interval_99.Contains(base[k].mean_nees_apriori) ? honest : optimistic)
        .push_back(k);
  }
  if (!honest.empty() || !optimistic.empty())
    html << " Honest covariance (mean NEES inside its 99 % interval): "
         << NameList(result.solver_names, honest) << (optimistic.empty() ? "" : "; not: ")
         << (optimistic.empty() ? "" : NameList(result.solver_names, optimistic)) << ".";
  if (most_outliers != nullptr) {
    std::vector<double> failure;
    for (const SolverStatistics& s : most_outliers->solvers) failure.push_back(1.0 - s.success_rate);
    double best = 1.0;
    for (const double f : failure) best = std::min(best, f);
    std::vector<size_t> robust;
    for (size_t k = 0; k < failure.size(); ++k)
      if (failure[k] <= best + one_sample + 1e-12) robust.push_back(k);
    html << " With " << FormatUnitless(100.0 * most_outliers->setting.outlier_fraction, 0)
         << " % outliers the best success rate ("
         << FormatUnitless(100.0 * (1.0 - best), 0) << " %) is "
         << NameList(result.solver_names, robust) << "'s.";
  }
  html << "</div>\n";
  return html.str();
}

// The verdict of a dataset comparison: who solves every image, who ties for the smallest residuals
// of the check marks (else of the inliers), the fastest of them.
std::string DatasetVerdict(const DatasetComparisonResult& result) {
  std::vector<double> residual, seconds;
  int most_solved = 0;
  for (const DatasetSolverSummary& s : result.summaries) most_solved = std::max(most_solved, s.solved);
  bool by_check = false;
  for (const DatasetSolverSummary& s : result.summaries)
    by_check = by_check || (s.solved > 0 && s.check_rmse_px > 0.0);
  for (const DatasetSolverSummary& s : result.summaries) {
    residual.push_back(s.solved == most_solved && s.solved > 0
                           ? (by_check ? s.check_rmse_px : s.rms_px)
                           : kNaN);
    seconds.push_back(s.median_seconds);
  }
  const std::vector<size_t> tied = TiedBest(residual, kTieFraction);
  std::ostringstream html;
  if (tied.empty())
    return "<div class=\"verdict bad\"><b>No solver oriented an image</b> (see the per-image "
           "table for the reasons).</div>\n";
  const size_t fastest = Fastest(seconds, tied);
  const DatasetSolverSummary& best = result.summaries[fastest];
  html << "<div class=\"verdict " << (most_solved == best.images ? "good" : "note")
       << "\"><b>Use " << HtmlEscape(best.solver) << ".</b> " << NameList(result.solver_names, tied)
       << (tied.size() > 1 ? " tie" : " is best") << " for the smallest "
       << (by_check ? "check-mark" : "inlier") << " residuals ("
       << FormatPixels(by_check ? best.check_rmse_px : best.rms_px) << " px RMS"
       << (tied.size() > 1 ? " within " + FormatUnitless(100.0 * kTieFraction, 0) + " %" : "")
       << ") among those orienting the most images (" << most_solved << " of " << best.images
       << ")";
  if (tied.size() > 1)
    html << "; " << HtmlEscape(best.solver) << " is the fastest of them ("
         << FormatSignificant(1e6 * best.median_seconds, 3) << " " << Utf8UnitName("us")
         << " per image)";
  html << ".";
  if (most_solved < best.images)
    html << " " << FormatCount(best.images - most_solved, "image")
         << " could not be oriented by any solver (see the per-image table).";
  html << "</div>\n";
  return html.str();
}

}  // namespace

std::vector<size_t> TiedBest(const std::vector<double>& values, double relative) {
  double best = std::numeric_limits<double>::infinity();
  for (const double v : values)
    if (std::isfinite(v)) best = std::min(best, v);
  std::vector<size_t> tied;
  if (!std::isfinite(best)) return tied;
  for (size_t k = 0; k < values.size(); ++k)
    if (std::isfinite(values[k]) && values[k] <= best + relative * std::abs(best)) tied.push_back(k);
  return tied;
}

std::string ComparisonGlossaryHtml() {
  static const std::vector<std::pair<std::string, std::string>> kTerms = {
      {"taylor_as_printed",
       "The seed note's Taylor linearisation solved by Gauss-Newton, with the partial derivatives "
       "exactly as printed in the note (its eq. 21 included, which has an error); kept to show "
       "what the printed equations give."},
      {"taylor", "The same Gauss-Newton with the corrected partial derivatives."},
      {"ceres_analytic",
       "Levenberg-Marquardt in Ceres on the collinearity cost with hand-derived (analytic) "
       "Jacobians."},
      {"ceres_autodiff",
       "The same with Jacobians by automatic differentiation; it should agree with ceres_analytic "
       "to rounding."},
      {"/none, /huber, /cauchy, /softl1",
       "The loss on the marks' residuals: none is plain least squares; the robust losses weigh "
       "large residuals down so that outliers pull less."},
      {"solved, success",
       "solved: a pose was returned (a block: the adjustment converged); success: and its centre "
       "is within the stated number of design sigmas of the truth."},
      {"iter, iterations", "Mean number of iterations of the solver (Gauss-Newton corrections, "
                           "Levenberg-Marquardt steps)."},
      {"pos RMSE, camera RMSE",
       "Root mean square of the distance between the estimated and the true camera centre, in "
       "the unit of the column's largest value (mm below 0.1 m, cm below 10 m, else m)."},
      {"rot RMSE", "Root mean square of the rotation error, in arc seconds."},
      {"d_ref pos, d_ref rot, max offset from Taylor, offset RMS, offset max",
       "RMS (or largest) difference of the camera centres and rotations to the reference solver "
       "(taylor when compared) on the same data and start."},
      {"d_frames pos, d_frames rot",
       "The same against the reference frames given with --reference."},
      {"check RMSE, reproj RMSE, RMS",
       "RMS image residual of the check marks, of the control marks, and of the inliers, in "
       "pixels; check beyond: check marks beyond the inlier threshold."},
      {"time, refine, t/ref, x Taylor",
       "Median time of one solve (microseconds per image, milliseconds per block), its "
       "refinement part, and its ratio to the reference solver's."},
      {"sigma0", "The a-posteriori standard deviation of unit weight: 1 when the residuals match "
                 "the stated accuracy of the marks."},
      {"NEES", "Normalised estimation error squared: the error against the solver's own "
               "covariance, e^T C^-1 e. Its mean is the number of parameters (6 for a pose, 3 for "
               "a camera centre) when the covariance is honest; above means too optimistic."},
      {"nees_ap, E[nees], 99% int, cov",
       "NEES with sigma0 = 1 (a-priori), its expectation with sigma0 estimated, the interval its "
       "mean falls in 99 % of the time when honest, and the verdict (ok, HIGH: too optimistic, "
       "low: too pessimistic)."},
  };
  return HtmlGlossary(kTerms);
}

namespace {

// A table's header as the page reads it: a unit in parentheses ("time (us)") in its UTF-8 name
// (Utf8UnitName: "time (µs)"); the console and Markdown tables keep the ASCII one.
std::vector<std::string> PageHeader(std::vector<std::string> header) {
  for (std::string& name : header)
    for (const char* unit : {"us", "um"}) {
      const std::string ascii = std::string("(") + unit + ")";
      const size_t at = name.find(ascii);
      if (at != std::string::npos) name.replace(at, ascii.size(), "(" + Utf8UnitName(unit) + ")");
    }
  return header;
}

}  // namespace

std::string RenderHtmlTable(const TextTable& table_in) {
  TextTable table = table_in;
  table.header = PageHeader(table.header);
  // Naming columns, repeated in every block: the first (first two for per-image tables).
  const size_t num_keys = std::min<size_t>(
      table.header.size(), !table.header.empty() && table.header[0] == "image" ? 2 : 1);
  const size_t num_values = table.header.size() - num_keys;
  if (num_values <= kMaxHtmlValueColumns)
    return HtmlTable(table.title, table.header, table.rows, table.notes);
  // Wider tables in blocks of columns of about equal width, one under the other: an A4 page
  // holds them at a readable size.
  const size_t num_blocks = (num_values + kMaxHtmlValueColumns - 1) / kMaxHtmlValueColumns;
  const size_t per_block = (num_values + num_blocks - 1) / num_blocks;
  std::string html;
  for (size_t b = 0; b < num_blocks; ++b) {
    const size_t first = num_keys + b * per_block;
    const size_t last = std::min(table.header.size(), first + per_block);
    auto pick = [&](const std::vector<std::string>& cells) {
      std::vector<std::string> out;
      for (size_t c = 0; c < num_keys; ++c) out.push_back(c < cells.size() ? cells[c] : "");
      for (size_t c = first; c < last; ++c) out.push_back(c < cells.size() ? cells[c] : "");
      return out;
    };
    std::vector<std::vector<std::string>> rows;
    for (const auto& row : table.rows) rows.push_back(pick(row));
    html += HtmlTable(b == 0 ? table.title : table.title + " (continued)", pick(table.header),
                      rows, b + 1 == num_blocks ? table.notes : std::vector<std::string>());
  }
  return html;
}

namespace {

// The Monte-Carlo page's Run section: the command, trials, sweep, solvers and the notes.
std::string MonteCarloRunHtml(const MonteCarloOptions& options, const MonteCarloResult& result,
                              const std::string& command_line) {
  std::ostringstream html;
  html << "<h2>Run</h2>\n<p>Command: <code>" << HtmlEscape(command_line) << "</code></p>\n";
  html << "<p>" << FormatCount(options.trials, "trial") << " per setting, sweep "
       << EnumName(options.sweep) << ", initial values " << EnumName(options.initial)
       << ", wall time " << FormatSignificant(result.wall_seconds, 3) << " s. Solvers: ";
  for (size_t s = 0; s < result.solver_names.size(); ++s)
    html << (s ? ", " : "") << "<code>" << HtmlEscape(result.solver_names[s]) << "</code>";
  html << ".</p>\n<ul class=\"notes\">\n";
  for (const std::string& note : MonteCarloNotes(options))
    html << "<li>" << HtmlEscape(note) << "</li>\n";
  html << "</ul>\n";
  return html.str();
}

// Metric of a solver in a setting, for the Monte-Carlo plots.
struct Metric {
  const char* name;
  const char* unit_label;  // short: the row's title names the metric
  bool log_y;
  bool rate;
  bool nees_reference;  // draw the dashed line at 6
  bool length;          // a length (m) drawn in the unit of the largest (core/units.h)
  double (*get)(const SolverStatistics&);
};
const Metric kPositionMetric{
    "position RMSE", "RMSE", true, false, false, true, [](const SolverStatistics& s) {
      return s.position_rmse_m;
    }};
const Metric kSuccessMetric{
    "success rate", "success (0 to 1)", false, true, false, false, [](const SolverStatistics& s) {
      return s.success_rate;
    }};
const Metric kNeesMetric{"mean NEES (sigma0 = 1)",
                         "NEES (unitless)",
                         true,
                         false,
                         true,
                         false,
                         [](const SolverStatistics& s) { return s.mean_nees_apriori; }};
const Metric kIterationsMetric{
    "mean iterations", "iterations", false, false, false, false, [](const SolverStatistics& s) {
      return s.mean_iterations;
    }};

// A metric's value as plotted: lengths in the page's one unit.
double PlottedValue(const Metric& metric, const SolverStatistics& s, LengthUnit position_unit) {
  return metric.length ? LengthIn(metric.get(s), position_unit) : metric.get(s);
}

// One row of small multiples (a panel per solver): `metric` over the settings `along` the axis.
std::string MetricPlotHtml(const MonteCarloResult& result, Scenario scenario,
                           const std::string& axis, const Metric& metric,
                           const std::vector<size_t>& along, LengthUnit position_unit) {
  LinePlot plot;
  plot.title = std::string(EnumName(scenario)) + ": " + metric.name + " vs " +
               (axis == "initial" ? "initial error" : axis);
  plot.x_label = AxisLabel(axis);
  plot.y_label = metric.length
                     ? std::string(metric.unit_label) + " (" + LengthUnitName(position_unit) + ")"
                     : metric.unit_label;
  plot.log_y = metric.log_y;
  if (metric.rate) plot.y_min = 0.0, plot.y_max = 1.0;
  if (metric.nees_reference) {
    plot.reference_y = 6.0;
    plot.reference_label = "6 (honest)";
  }
  // Logarithmic only when the values span more than a factor of 30; values below 1e-6 of
  // the largest (noise 0: rounding) count as 0, which a linear axis shows as such.
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (size_t k : along)
    for (const SolverStatistics& s : result.settings[k].solvers)
      if (std::isfinite(PlottedValue(metric, s, position_unit)))
        hi = std::max(hi, PlottedValue(metric, s, position_unit));
  for (size_t k : along)
    for (const SolverStatistics& s : result.settings[k].solvers) {
      const double v = PlottedValue(metric, s, position_unit);
      if (std::isfinite(v) && v > 1e-6 * hi) lo = std::min(lo, v);
    }
  if (plot.log_y && std::isfinite(lo) && hi < 30.0 * lo && lo > 0.0 && !(hi < 1e-3))
    plot.log_y = false;
  for (size_t s = 0; s < result.solver_names.size(); ++s) {
    PlotSeries series;
    series.label = result.solver_names[s];
    for (size_t k : along) {
      series.x.push_back(PlotX(result.settings[k].setting, axis));
      series.y.push_back(PlottedValue(metric, result.settings[k].solvers[s], position_unit));
    }
    plot.series.push_back(series);
  }
  return "<div class=\"plots\">" + RenderSmallMultiplesSvg(plot) + "</div>\n";
}

// Time per solve at the scenario's baseline setting (the first of the scenario); the
// refinement part is in the table.
std::string BaselineTimeHtml(const MonteCarloResult& result, Scenario scenario) {
  for (const SettingResult& setting : result.settings) {
    if (setting.setting.scenario != scenario) continue;
    BarPlot bars;
    bars.title = std::string(EnumName(scenario)) + ": median time per solve (" +
                 setting.setting.axis + " setting)";
    bars.value_label = "microseconds per image (ResectImage wall time)";
    for (const SolverStatistics& s : setting.solvers) {
      bars.labels.push_back(s.solver);
      bars.values.push_back(s.median_seconds * 1e6);
    }
    return "<div class=\"plots\">" + RenderBarPlotSvg(bars) + "</div>\n";
  }
  return "";
}

// Every setting of the scenario in one table: the header once, a section per setting.
std::string ScenarioTableHtml(const MonteCarloResult& result, const std::vector<TextTable>& tables,
                              Scenario scenario) {
  std::vector<TableSection> sections;
  const std::string prefix = std::string(EnumName(scenario)) + ": ";
  std::vector<std::string> header;
  for (size_t k = 0; k < result.settings.size(); ++k) {
    if (result.settings[k].setting.scenario != scenario) continue;
    const TextTable& table = tables[k];
    if (header.empty()) header = PageHeader(table.header);
    TableSection section;
    section.heading =
        table.title.rfind(prefix, 0) == 0 ? table.title.substr(prefix.size()) : table.title;
    section.rows = table.rows;
    section.notes = table.notes;
    sections.push_back(std::move(section));
  }
  return HtmlSectionedTable(std::string(EnumName(scenario)) + ": every setting", header, sections);
}

// One scenario's section: a row of small multiples per metric and sweep axis, the baseline's
// time, the table of every setting.
std::string ScenarioHtml(const MonteCarloOptions& options, const MonteCarloResult& result,
                         const std::vector<TextTable>& tables, Scenario scenario,
                         LengthUnit position_unit) {
  static const std::vector<std::pair<std::string, std::vector<Metric>>> kPlots = {
      {"noise", {kPositionMetric, kNeesMetric}},
      {"outliers", {kPositionMetric, kSuccessMetric}},
      {"initial", {kSuccessMetric, kIterationsMetric}},
      {"control", {kPositionMetric, kSuccessMetric}},
  };
  std::ostringstream html;
  html << "<h2>Scenario " << EnumName(scenario) << "</h2>\n";
  for (const auto& [axis, metrics] : kPlots) {
    const std::vector<size_t> along = SettingsAlongAxis(options, result, scenario, axis);
    if (along.empty()) continue;
    if (axis == "initial") {
      html << "<p>Initial error: +-";
      for (size_t k = 0; k < along.size(); ++k)
        html << (k ? "/" : "")
             << FormatScaledLength(result.settings[along[k]].setting.initial_error.position_m);
      html << " in position with the angle errors on the x axis.</p>\n";
    }
    for (const Metric& metric : metrics)
      html << MetricPlotHtml(result, scenario, axis, metric, along, position_unit);
  }
  html << BaselineTimeHtml(result, scenario) << ScenarioTableHtml(result, tables, scenario);
  return html.str();
}

}  // namespace

std::string MonteCarloHtml(const MonteCarloOptions& options, const MonteCarloResult& result,
                           const std::string& command_line) {
  std::ostringstream html;
  const std::string title = "photopose compare: Monte-Carlo comparison of the pose solvers";
  html << HtmlPageOpen(title, "Which pose solver to use: a Monte-Carlo comparison");
  html << "<h2>Verdict</h2>\n";
  for (Scenario scenario : options.scenarios) html << ScenarioVerdict(options, result, scenario);
  html << "<h2>Glossary</h2>\n" << ComparisonGlossaryHtml();
  html << MonteCarloRunHtml(options, result, command_line);
  const std::vector<TextTable> tables = MonteCarloTables(options, result);
  // Every position plot of the page in one unit, that of the largest RMSE.
  std::vector<double> position_values;
  for (const SettingResult& setting : result.settings)
    for (const SolverStatistics& s : setting.solvers)
      position_values.push_back(kPositionMetric.get(s));
  const LengthUnit position_unit = LengthUnitFor(LargestMagnitude(position_values));
  for (Scenario scenario : options.scenarios)
    html << ScenarioHtml(options, result, tables, scenario, position_unit);
  html << HtmlPageClose();
  return html.str();
}

std::string DatasetHtml(const DatasetComparisonResult& result, const std::string& command_line) {
  std::ostringstream html;
  const std::string title = "photopose compare: the pose solvers on a dataset";
  html << HtmlPageOpen(title, "Which pose solver to use on this dataset");
  html << "<h2>Verdict</h2>\n" << DatasetVerdict(result);
  html << "<h2>Glossary</h2>\n" << ComparisonGlossaryHtml();
  html << "<h2>Run</h2>\n<p>Command: <code>" << HtmlEscape(command_line) << "</code></p>\n";
  const std::vector<TextTable> tables = DatasetTables(result);
  html << "<div class=\"plots\">\n";
  BarPlot time;
  time.title = "median time per image";
  time.value_label = "microseconds per image (ResectImage wall time)";
  // The differences in the unit of the largest of each plot (core/units.h).
  std::vector<double> differences, references;
  for (const DatasetSolverSummary& s : result.summaries) {
    differences.push_back(s.compared > 0 ? s.difference_position_m : kNaN);
    references.push_back(s.referenced > 0 ? s.reference_position_m : kNaN);
  }
  const LengthUnit difference_unit = LengthUnitFor(LargestMagnitude(differences));
  const LengthUnit reference_unit = LengthUnitFor(LargestMagnitude(references));
  BarPlot difference;
  difference.title = "RMS position difference to " + result.reference_solver;
  difference.value_label = std::string("RMS position difference (") +
                           LengthUnitName(difference_unit) +
                           "; n/a: the solver itself or none solved)";
  BarPlot reference = difference;
  reference.title = "RMS position difference to the reference frames";
  reference.value_label =
      std::string("RMS position difference (") + LengthUnitName(reference_unit) + ")";
  reference.values.clear();
  for (size_t k = 0; k < result.summaries.size(); ++k) {
    const DatasetSolverSummary& s = result.summaries[k];
    time.labels.push_back(s.solver);
    time.values.push_back(s.median_seconds * 1e6);
    difference.labels.push_back(s.solver);
    difference.values.push_back(LengthIn(differences[k], difference_unit));
    reference.labels.push_back(s.solver);
    reference.values.push_back(LengthIn(references[k], reference_unit));
  }
  html << RenderBarPlotSvg(time) << "\n" << RenderBarPlotSvg(difference) << "\n";
  if (result.has_reference) html << RenderBarPlotSvg(reference) << "\n";
  html << "</div>\n";
  for (const TextTable& table : tables) html << RenderHtmlTable(table);
  html << HtmlPageClose();
  return html.str();
}

// ------------------------------------------------------------------ block comparisons

namespace {

// Solvers within this fraction of the best camera RMSE tie: with a few blocks per setting the
// RMSE itself is uncertain by several per cent (unitless).
constexpr double kBlockTieFraction = 0.05;

// What the baseline setting says of each block solver beside its accuracy: failed blocks,
// covariances that are not honest, what the printed partial derivatives cost.
std::vector<std::string> BlockFindings(const BlockComparisonResult& result) {
  const std::vector<BlockSolverStatistics>& base = result.statistics[0];
  std::vector<std::string> findings;
  for (size_t s = 0; s < base.size(); ++s) {
    const BlockSolverStatistics& st = base[s];
    const std::string name = "<b>" + HtmlEscape(result.solver_names[s]) + "</b>";
    if (st.successes < st.trials)
      findings.push_back(name + " failed " + std::to_string(st.trials - st.successes) + " of " +
                         std::to_string(st.trials) + " blocks.");
    if (st.nees_count > 0 && !st.nees_interval_95.Contains(st.mean_nees))
      findings.push_back(name + ": covariance not honest (mean NEES " +
                         FormatUnitless(st.mean_nees) + ", expected " +
                         FormatUnitless(st.nees_interval_95.lower) + " to " +
                         FormatUnitless(st.nees_interval_95.upper) + ").");
    if (result.solver_names[s] == "taylor_as_printed" && std::isfinite(st.max_position_offset_m))
      findings.push_back(
          "The partial derivatives as printed in the seed note (its eq. 21) move camera centres "
          "by up to " +
          FormatLengthWithUnit(st.max_position_offset_m) +
          " from the corrected linearisation in these blocks (camera RMSE " +
          FormatLengthWithUnit(st.camera_rmse_m) + " against the truth).");
  }
  return findings;
}

// The verdict from the baseline setting: the fastest of the solvers tied for the most accurate
// camera positions among those adjusting the most blocks, and the findings.
std::string BlockVerdictHtml(const BlockComparisonResult& result) {
  if (result.statistics.empty()) return "";
  const std::vector<BlockSolverStatistics>& base = result.statistics[0];
  std::vector<double> rmse, seconds;
  int most = 0;
  for (const BlockSolverStatistics& st : base) most = std::max(most, st.successes);
  for (const BlockSolverStatistics& st : base) {
    rmse.push_back(st.successes == most && most > 0 ? st.camera_rmse_m : std::nan(""));
    seconds.push_back(st.mean_seconds);
  }
  const std::vector<size_t> tied = TiedBest(rmse, kBlockTieFraction);
  const std::vector<std::string> findings = BlockFindings(result);
  std::ostringstream html;
  if (tied.empty()) {
    html << "<div class=\"verdict bad\"><b>No solver adjusted a block at the baseline.</b>";
  } else {
    const size_t fastest = Fastest(seconds, tied);
    html << "<div class=\"verdict " << (findings.empty() ? "good" : "note") << "\"><b>Use "
         << HtmlEscape(result.solver_names[fastest]) << ".</b> At the baseline ("
         << HtmlEscape(result.settings[0].Label()) << ") ";
    for (size_t k = 0; k < tied.size(); ++k)
      html << (k == 0 ? "" : (k + 1 == tied.size() ? " and " : ", ")) << "<b>"
           << HtmlEscape(result.solver_names[tied[k]]) << "</b>";
    html << (tied.size() > 1 ? " tie for the most accurate camera positions (RMSE within " +
                                   FormatUnitless(100.0 * kBlockTieFraction, 0) + " % of "
                             : " has the most accurate camera positions (RMSE ")
         << FormatLengthWithUnit(base[tied.front()].camera_rmse_m) << ")";
    if (tied.size() > 1)
      html << "; " << HtmlEscape(result.solver_names[fastest]) << " is the fastest of them ("
           << FormatSignificant(1e3 * base[fastest].mean_seconds, 3) << " ms per block)";
    html << ".";
  }
  if (!findings.empty()) {
    html << "<ul>";
    for (const std::string& f : findings) html << "<li>" << f << "</li>";
    html << "</ul>";
  }
  html << "</div>\n";
  return html.str();
}

// How the block comparison measures: the same block and start for all, the RMSEs, NEES, time.
std::string BlockComparisonNotesHtml() {
  return "<ul class=\"notes\">\n"
         "<li>Every solver adjusts the same simulated block from the same perturbed start "
         "(core/simulation/synthetic_block.h), with the stated accuracies equal to the true "
         "noise and the default rejection of marks beyond 4.5 sigma.</li>\n"
         "<li>Camera RMSE: per axis, over every image of the successful blocks, of the adjusted "
         "centre minus the true one. Check RMSE: the check points intersected from the adjusted "
         "images against their true positions.</li>\n"
         "<li>NEES here: of the camera centres (3 degrees of freedom; 3 when the reported "
         "covariance is honest), with its 95 % interval.</li>\n"
         "<li>Time: one adjustment, single-threaded, including its statistics; x Taylor: the "
         "ratio to the corrected Taylor solver in the same run.</li>\n</ul>\n";
}

// Small multiples: camera RMSE by solver, one panel per setting, every panel in one unit, that
// of the largest camera RMSE (core/units.h).
std::string CameraAccuracyPlotsHtml(const BlockComparisonResult& result) {
  std::vector<double> camera_rmse;
  for (const auto& per_setting : result.statistics)
    for (const BlockSolverStatistics& st : per_setting)
      camera_rmse.push_back(st.successes > 0 ? st.camera_rmse_m : std::nan(""));
  const LengthUnit camera_unit = LengthUnitFor(LargestMagnitude(camera_rmse));
  std::string html;
  for (size_t setting = 0; setting < result.settings.size(); ++setting) {
    BarPlot bars;
    bars.title = result.settings[setting].Label();
    bars.value_label = std::string("camera RMSE (") + LengthUnitName(camera_unit) + ")";
    for (size_t s = 0; s < result.solver_names.size(); ++s) {
      const BlockSolverStatistics& st = result.statistics[setting][s];
      bars.labels.push_back(result.solver_names[s]);
      bars.values.push_back(
          st.successes > 0 ? LengthIn(st.camera_rmse_m, camera_unit) : std::nan(""));
    }
    html += RenderBarPlotSvg(bars) + "\n";
  }
  return html;
}

}  // namespace

std::string BlockComparisonHtml(const BlockComparisonOptions& options,
                                const BlockComparisonResult& result,
                                const std::string& command_line) {
  std::ostringstream html;
  html << HtmlPageOpen("photopose compare: blocks", "Which block solver to use");
  html << "<h2>Verdict</h2>\n" << BlockVerdictHtml(result);
  html << "<h2>Glossary</h2>\n" << ComparisonGlossaryHtml() << BlockComparisonNotesHtml();
  html << "<h2>Camera accuracy per setting</h2>\n<div class=\"plots\">\n"
       << CameraAccuracyPlotsHtml(result);
  html << "</div>\n<h2>Tables</h2>\n";
  for (const TextTable& table : BlockComparisonTables(options, result))
    html << RenderHtmlTable(table) << "\n";
  html << "<p>" << FormatCount(static_cast<long long>(result.settings.size() * options.trials),
                               "block")
       << " in " << FormatSignificant(result.wall_seconds, 3) << " s.</p>\n"
       << "<h2>Run</h2>\n<p>Command: <code>" << HtmlEscape(command_line) << "</code></p>\n"
       << HtmlPageClose();
  return html.str();
}

std::string BlockDatasetHtml(const BlockDatasetResult& result, const std::string& command_line) {
  std::ostringstream html;
  html << HtmlPageOpen("photopose compare: a block", "The block solvers on one block")
       << "<p><code>" << HtmlEscape(command_line)
       << "</code></p>\n<p>No truth: every solver's camera centres "
       << "against " << HtmlEscape(result.reference.empty() ? "no reference" : result.reference)
       << "; check points against their surveyed coordinates.</p>\n"
       << RenderHtmlTable(BlockDatasetTable(result)) << "\n"
       << HtmlPageClose();
  return html.str();
}

}  // namespace photopose::cli
