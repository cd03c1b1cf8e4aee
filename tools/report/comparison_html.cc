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

}  // namespace

std::string RenderHtmlTable(const TextTable& table) {
  return HtmlTable(table.title, table.header, table.rows, table.notes);
}

std::string MonteCarloHtml(const MonteCarloOptions& options, const MonteCarloResult& result,
                           const std::string& command_line) {
  std::ostringstream html;
  const std::string title = "photopose compare: Monte-Carlo comparison of the pose solvers";
  html << HtmlPageOpen(title, title);
  html << "<p>Command: <code>" << HtmlEscape(command_line) << "</code></p>\n";
  html << "<p>" << options.trials << " trials per setting, sweep " << EnumName(options.sweep)
       << ", initial values " << EnumName(options.initial) << ", wall time "
       << ReportFixed(result.wall_seconds, 1) << " s. Solvers: ";
  for (size_t s = 0; s < result.solver_names.size(); ++s)
    html << (s ? ", " : "") << "<code>" << HtmlEscape(result.solver_names[s]) << "</code>";
  html << ".</p>\n<ul class=\"notes\">\n";
  for (const std::string& note : MonteCarloNotes(options))
    html << "<li>" << HtmlEscape(note) << "</li>\n";
  html << "</ul>\n";

  const std::vector<TextTable> tables = MonteCarloTables(options, result);
  for (Scenario scenario : options.scenarios) {
    html << "<h2>Scenario " << EnumName(scenario) << "</h2>\n<div class=\"plots\">\n";
    // Metric of a solver in a setting, for the plots.
    struct Metric {
      const char* name;
      const char* unit_label;
      bool log_y;
      bool rate;
      bool nees_reference;  // draw the dashed line at 6
      double (*get)(const SolverStatistics&);
    };
    const Metric position{
        "position RMSE", "position RMSE (m)", true, false, false, [](const SolverStatistics& s) {
          return s.position_rmse_m;
        }};
    const Metric success{"success rate", "success rate",
                         false,          true,
                         false,          [](const SolverStatistics& s) { return s.success_rate; }};
    const Metric nees{"mean NEES (sigma0 = 1)",
                      "mean NEES, a-priori covariance",
                      true,
                      false,
                      true,
                      [](const SolverStatistics& s) { return s.mean_nees_apriori; }};
    const Metric iterations{
        "mean iterations", "iterations", false, false, false, [](const SolverStatistics& s) {
          return s.mean_iterations;
        }};
    const std::vector<std::pair<std::string, std::vector<Metric>>> plots = {
        {"noise", {position, nees}},
        {"outliers", {position, success}},
        {"initial", {success, iterations}},
        {"control", {position, success}},
    };
    for (const auto& [axis, metrics] : plots) {
      const std::vector<size_t> along = SettingsAlongAxis(options, result, scenario, axis);
      if (along.empty()) continue;
      for (const Metric& metric : metrics) {
        LinePlot plot;
        plot.title = std::string(EnumName(scenario)) + ": " + metric.name + " vs " +
                     (axis == "initial" ? "initial error" : axis);
        plot.x_label = AxisLabel(axis);
        if (axis == "initial") {
          plot.x_label += "; position +-";
          for (size_t k = 0; k < along.size(); ++k)
            plot.x_label +=
                (k ? "/" : "") +
                ReportNumber(result.settings[along[k]].setting.initial_error.position_m, "%g");
          plot.x_label += " m";
        }
        plot.y_label = metric.unit_label;
        plot.log_y = metric.log_y;
        if (metric.rate) plot.y_min = 0.0, plot.y_max = 1.0;
        if (metric.nees_reference) {
          plot.reference_y = 6.0;
          plot.reference_label = "6 (honest)";
        }
        // Logarithmic only when the values span more than a factor of 30.
        double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
        for (size_t k : along)
          for (const SolverStatistics& s : result.settings[k].solvers) {
            const double v = metric.get(s);
            if (std::isfinite(v) && v > 0.0) lo = std::min(lo, v), hi = std::max(hi, v);
          }
        if (plot.log_y && std::isfinite(lo) && hi < 30.0 * lo && lo > 0.0 && !(hi < 1e-3))
          plot.log_y = false;
        for (size_t s = 0; s < result.solver_names.size(); ++s) {
          PlotSeries series;
          series.label = result.solver_names[s];
          for (size_t k : along) {
            series.x.push_back(PlotX(result.settings[k].setting, axis));
            series.y.push_back(metric.get(result.settings[k].solvers[s]));
          }
          plot.series.push_back(series);
        }
        html << RenderLinePlotSvg(plot) << "\n";
      }
    }
    // Time per solve at the scenario's baseline setting (the first of the scenario).
    for (const SettingResult& setting : result.settings) {
      if (setting.setting.scenario != scenario) continue;
      BarPlot bars;
      bars.title = std::string(EnumName(scenario)) + ": median time per solve (" +
                   setting.setting.axis + " setting)";
      bars.value_label = "microseconds per image (ResectImage wall time)";
      BarPlot refinement = bars;
      refinement.title = std::string(EnumName(scenario)) + ": median refinement time (" +
                         setting.setting.axis + " setting)";
      refinement.value_label = "microseconds per image (the solver's own iterations)";
      for (const SolverStatistics& s : setting.solvers) {
        bars.labels.push_back(s.solver);
        bars.values.push_back(s.median_seconds * 1e6);
        refinement.labels.push_back(s.solver);
        refinement.values.push_back(s.median_refinement_seconds * 1e6);
      }
      html << RenderBarPlotSvg(bars) << "\n" << RenderBarPlotSvg(refinement) << "\n";
      break;
    }
    html << "</div>\n";
    for (size_t k = 0; k < result.settings.size(); ++k)
      if (result.settings[k].setting.scenario == scenario) {
        html << RenderHtmlTable(tables[k]);
      }
  }
  html << HtmlPageClose();
  return html.str();
}

std::string DatasetHtml(const DatasetComparisonResult& result, const std::string& command_line) {
  std::ostringstream html;
  const std::string title = "photopose compare: the pose solvers on a dataset";
  html << HtmlPageOpen(title, title);
  html << "<p>Command: <code>" << HtmlEscape(command_line) << "</code></p>\n";
  const std::vector<TextTable> tables = DatasetTables(result);
  html << "<div class=\"plots\">\n";
  BarPlot time;
  time.title = "median time per image";
  time.value_label = "microseconds per image (ResectImage wall time)";
  BarPlot difference;
  difference.title = "RMS position difference to " + result.reference_solver;
  difference.value_label = "metres (n/a: the solver itself or none solved)";
  BarPlot reference = difference;
  reference.title = "RMS position difference to the reference frames";
  reference.value_label = "metres";
  for (const DatasetSolverSummary& s : result.summaries) {
    time.labels.push_back(s.solver);
    time.values.push_back(s.median_seconds * 1e6);
    difference.labels.push_back(s.solver);
    difference.values.push_back(s.compared > 0 ? s.difference_position_m : kNaN);
    reference.labels.push_back(s.solver);
    reference.values.push_back(s.referenced > 0 ? s.reference_position_m : kNaN);
  }
  html << RenderBarPlotSvg(time) << "\n" << RenderBarPlotSvg(difference) << "\n";
  if (result.has_reference) html << RenderBarPlotSvg(reference) << "\n";
  html << "</div>\n";
  for (const TextTable& table : tables) html << RenderHtmlTable(table);
  html << HtmlPageClose();
  return html.str();
}

}  // namespace photopose::cli
