#include "tools/compare/block_comparison.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <limits>
#include <mutex>
#include <sstream>

#include "core/parallel.h"
#include "core/simulation/synthetic_block.h"
#include "core/statistics.h"
#include "solvers/bundle/taylor_bundle.h"
#include "tools/commands/cli_common.h"
#include "tools/report/comparison_html.h"
#include "tools/report/html_kit.h"

namespace photopose::cli {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
using Clock = std::chrono::steady_clock;


// What one solver gave on one block.
struct TrialOutcome {
  bool success = false;
  std::string failure;
  std::vector<Eigen::Vector3d> centres;  // per image (empty on failure)
  double camera_ssq = 0.0;               // sum over images of |centre - truth|^2
  int num_images = 0;
  double check_ssq = 0.0;
  int num_checks = 0;
  double nees_sum = 0.0;
  int nees_count = 0;
  int iterations = 0;
  double seconds = 0.0;
};

TrialOutcome SolveBlock(const BlockSolverVariant& variant, const Block& start,
                        const SyntheticBlockTruth& truth) {
  TrialOutcome out;
  Block block = start;
  BundleAdjustmentOptions options;
  options.solver.num_threads = 1;
  options.solver.jacobian = variant.jacobian;
  options.robustness.tie_loss = variant.loss;
  // Covariances yes (NEES); per-observation tests no, so that both solvers reject marks by the same
  // rule (whitened residual beyond 4.5 max(1, sigma0)).
  options.statistics.observation_diagnostics = false;
  BundleAdjustmentResult result;
  const Clock::time_point begin = Clock::now();
  const Status status =
      BundleAdjustWithSolver(variant.solver, options, BundleAdjustmentConfig(), &block, &result);
  out.seconds = std::chrono::duration<double>(Clock::now() - begin).count();
  out.iterations = result.summary.iterations;
  if (!status.ok()) {
    out.failure = status.message();
    return out;
  }
  if (!result.summary.IsSolutionUsable()) {
    out.failure = result.summary.message;
    return out;
  }
  out.success = true;
  for (size_t i = 0; i < block.images.size(); ++i) {
    const Eigen::Vector3d centre = block.images[i].eo->center_in_ground();
    out.centres.push_back(centre);
    const Eigen::Vector3d error = centre - truth.eo[i].center_in_ground();
    out.camera_ssq += error.squaredNorm();
    ++out.num_images;
    if (i < result.images.size() && result.images[i].has_covariance) {
      const Eigen::Matrix3d C = result.images[i].covariance.topLeftCorner<3, 3>();
      const Eigen::LDLT<Eigen::Matrix3d> ldlt(C);
      if (ldlt.info() == Eigen::Success && ldlt.isPositive()) {
        out.nees_sum += error.dot(ldlt.solve(error));
        ++out.nees_count;
      }
    }
  }
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    if (point.role != PointRole::kCheck || p >= result.points.size()) continue;
    const BundlePointResult& r = result.points[p];
    if (!r.error_m || !point.surveyed_m) continue;
    // The intersected position (surveyed + error) against the true one.
    out.check_ssq += (*point.surveyed_m + *r.error_m - truth.points_m[p]).squaredNorm();
    ++out.num_checks;
  }
  return out;
}

}  // namespace

std::string BlockSolverVariant::Name() const {
  if (solver != PoseSolver::kCeres) return EnumName(solver);
  return std::string("ceres_") + EnumName(jacobian) + "/" + EnumName(loss);
}

Status ParseBlockSolverVariants(const std::string& solvers, const std::string& losses,
                                std::vector<BlockSolverVariant>* variants) {
  variants->clear();
  std::vector<LossType> loss_list;
  for (const std::string& name : SplitCommaList(losses)) {
    if (name.empty()) continue;
    std::vector<LossType> add(std::begin(kBundleTieLosses), std::end(kBundleTieLosses));
    if (name != "all") {
      add.resize(1);
      if (!ParseEnum(name, &add[0]) || !IsBundleTieLoss(add[0]))
        return Status::Error("--losses: '" + name +
                             "' is not a tie-mark loss of the block solvers (" +
                             EnumNameList(kBundleTieLosses) + ")");
    }
    for (const LossType loss : add)
      if (std::find(loss_list.begin(), loss_list.end(), loss) == loss_list.end())
        loss_list.push_back(loss);
  }
  if (loss_list.empty()) loss_list.push_back(LossType::kNone);
  for (const std::string& name : SplitCommaList(solvers)) {
    if (name.empty()) continue;
    const std::vector<std::string> names =
        name == "all"
            ? std::vector<std::string>{"taylor_as_printed", "taylor", "ceres_analytic",
                                       "ceres_autodiff"}
            : std::vector<std::string>{name};
    for (const std::string& n : names) {
      std::vector<BlockSolverVariant> add;
      BlockSolverVariant taylor;
      if ((n == "taylor" || n == "taylor_as_printed") && ParseEnum(n, &taylor.solver)) {
        add.push_back(taylor);
      } else if (n == "ceres_analytic" || n == "ceres_autodiff") {
        for (const auto loss : loss_list) {
          BlockSolverVariant v;
          v.jacobian = n == "ceres_analytic" ? JacobianType::kAnalytic : JacobianType::kAutodiff;
          v.loss = loss;
          add.push_back(v);
        }
      } else {
        return Status::Error("--solvers: unknown solver '" + n +
                             "' (taylor_as_printed, taylor, ceres_analytic, ceres_autodiff, all)");
      }
      for (const BlockSolverVariant& v : add) {
        const bool seen = std::any_of(variants->begin(), variants->end(),
                                      [&](const BlockSolverVariant& w) { return w.Name() == v.Name(); });
        if (!seen) variants->push_back(v);
      }
    }
  }
  if (variants->empty()) return Status::Error("--solvers: no solver given");
  return Status::Ok();
}

bool BlockComparisonOptions::IsValid(std::string* why) const {
  auto fail = [why](const std::string& text) {
    if (why != nullptr) *why = text;
    return false;
  };
  if (solvers.empty()) return fail("no solver");
  if (noise_px.empty() || tie_blunders.empty() || tie_points.empty() || gnss_sigma_m.empty())
    return fail("every sweep axis needs at least one value");
  for (const double v : noise_px)
    if (!(v >= 0.0 && v <= 100.0)) return fail("noise must be in [0, 100] px");
  for (const int v : tie_blunders)
    if (v < 0 || v > 100000) return fail("tie blunders must be in [0, 100000]");
  for (const long long v : tie_points)
    if (v < 10 || v > 1000000) return fail("tie points must be in [10, 1000000]");
  for (const double v : gnss_sigma_m)
    if (!(v > 0.0 && v <= 100.0)) return fail("GNSS sigma must be in (0, 100] m");
  if (lines < 1 || lines > 100 || images_per_line < 2 || images_per_line > 100)
    return fail("a block has 1-100 lines of 2-100 images");
  if (trials < 1 || trials > 10000) return fail("trials must be in [1, 10000]");
  if (num_threads < 0 || num_threads > 1024) return fail("threads must be in [0, 1024]");
  return true;
}

std::string BlockSetting::Label() const {
  std::ostringstream os;
  os << "noise " << noise_px << " px, " << tie_blunders << " tie blunders, " << tie_points
     << " tie points, GNSS " << gnss_sigma_m << " m";
  return os.str();
}

Status RunBlockComparison(const BlockComparisonOptions& options, BlockComparisonResult* result) {
  *result = BlockComparisonResult();
  std::string why;
  if (!options.IsValid(&why)) return Status::Error(why);
  const Clock::time_point start = Clock::now();

  // Settings: the baseline, then each further value of one axis.
  BlockSetting base;
  base.axis = "baseline";
  base.noise_px = options.noise_px[0];
  base.tie_blunders = options.tie_blunders[0];
  base.tie_points = options.tie_points[0];
  base.gnss_sigma_m = options.gnss_sigma_m[0];
  result->settings.push_back(base);
  for (size_t k = 1; k < options.noise_px.size(); ++k) {
    BlockSetting s = base;
    s.axis = "noise_px";
    s.noise_px = options.noise_px[k];
    result->settings.push_back(s);
  }
  for (size_t k = 1; k < options.tie_blunders.size(); ++k) {
    BlockSetting s = base;
    s.axis = "tie_blunders";
    s.tie_blunders = options.tie_blunders[k];
    result->settings.push_back(s);
  }
  for (size_t k = 1; k < options.tie_points.size(); ++k) {
    BlockSetting s = base;
    s.axis = "tie_points";
    s.tie_points = options.tie_points[k];
    result->settings.push_back(s);
  }
  for (size_t k = 1; k < options.gnss_sigma_m.size(); ++k) {
    BlockSetting s = base;
    s.axis = "gnss_sigma_m";
    s.gnss_sigma_m = options.gnss_sigma_m[k];
    result->settings.push_back(s);
  }
  for (const BlockSolverVariant& v : options.solvers) result->solver_names.push_back(v.Name());
  const size_t num_settings = result->settings.size();
  const size_t num_solvers = options.solvers.size();
  const size_t jobs = num_settings * static_cast<size_t>(options.trials);
  result->images_per_block = options.lines * options.images_per_line;

  // [job][solver]
  std::vector<std::vector<TrialOutcome>> outcomes(jobs);
  std::vector<std::string> errors(jobs);
  std::atomic<size_t> done{0};
  std::mutex progress_mutex;
  ParallelFor(jobs, options.num_threads, [&](size_t job) {
    const BlockSetting& setting = result->settings[job / options.trials];
    const int trial = static_cast<int>(job % options.trials);
    SyntheticBlockOptions o;
    o.seed = options.seed + static_cast<uint64_t>(trial);
    o.num_lines = options.lines;
    o.images_per_line = options.images_per_line;
    o.num_tie_points = setting.tie_points;
    o.mark_sigma_px = setting.noise_px;
    o.mark_accuracy_px = std::max(setting.noise_px, 0.05);  // stated = true (0 noise: 0.05)
    o.gnss_sigma_m = Eigen::Vector3d(setting.gnss_sigma_m, setting.gnss_sigma_m,
                                     2.0 * setting.gnss_sigma_m);
    o.num_tie_blunders = setting.tie_blunders;
    o.control_sigma_m = 0.005;
    Block block;
    SyntheticBlockTruth truth;
    const Status made = MakeSyntheticBlock(o, &block, &truth);
    if (!made.ok()) {
      errors[job] = setting.Label() + ", trial " + std::to_string(trial) + ": " + made.message();
    } else {
      for (const BlockSolverVariant& variant : options.solvers)
        outcomes[job].push_back(SolveBlock(variant, block, truth));
    }
    const size_t finished = ++done;
    if (options.progress) {
      const std::lock_guard<std::mutex> lock(progress_mutex);
      options.progress(finished, jobs);
    }
  });
  for (const std::string& error : errors)
    if (!error.empty()) return Status::Error(error);

  // The corrected Taylor solver, when compared, is the baseline of time and position offsets.
  int taylor = -1;
  for (size_t s = 0; s < num_solvers; ++s)
    if (options.solvers[s].solver == PoseSolver::kTaylor) taylor = static_cast<int>(s);

  result->statistics.assign(num_settings, std::vector<BlockSolverStatistics>(num_solvers));
  for (size_t setting = 0; setting < num_settings; ++setting) {
    for (size_t s = 0; s < num_solvers; ++s) {
      BlockSolverStatistics& st = result->statistics[setting][s];
      double camera_ssq = 0.0, check_ssq = 0.0, nees = 0.0, iterations = 0.0, seconds = 0.0;
      int cameras = 0, checks = 0;
      for (int trial = 0; trial < options.trials; ++trial) {
        const std::vector<TrialOutcome>& job = outcomes[setting * options.trials + trial];
        const TrialOutcome& o = job[s];
        ++st.trials;
        iterations += o.iterations;
        seconds += o.seconds;
        if (!o.success) {
          if (st.failures.size() < 3) st.failures.push_back(o.failure);
          continue;
        }
        ++st.successes;
        camera_ssq += o.camera_ssq;
        cameras += o.num_images;
        check_ssq += o.check_ssq;
        checks += o.num_checks;
        nees += o.nees_sum;
        st.nees_count += o.nees_count;
        if (taylor >= 0 && job[taylor].success) {
          for (size_t i = 0; i < o.centres.size(); ++i) {
            st.max_position_offset_m = std::max(
                st.max_position_offset_m, (o.centres[i] - job[taylor].centres[i]).norm());
          }
        }
      }
      st.camera_rmse_m = cameras > 0 ? std::sqrt(camera_ssq / (3.0 * cameras)) : kNaN;
      st.check_rmse_m = checks > 0 ? std::sqrt(check_ssq / (3.0 * checks)) : kNaN;
      st.mean_nees = st.nees_count > 0 ? nees / st.nees_count : kNaN;
      if (st.nees_count > 0) {
        const double dof = 3.0 * st.nees_count;
        st.nees_interval_95 = NeesInterval{ChiSquaredQuantile(0.025, dof) / st.nees_count,
                                           ChiSquaredQuantile(0.975, dof) / st.nees_count};
      } else {
        st.nees_interval_95 = NeesInterval{kNaN, kNaN};
      }
      st.mean_iterations = iterations / st.trials;
      st.mean_seconds = seconds / st.trials;
    }
    for (size_t s = 0; s < num_solvers; ++s) {
      BlockSolverStatistics& st = result->statistics[setting][s];
      st.time_ratio_to_taylor =
          taylor >= 0 ? st.mean_seconds / result->statistics[setting][taylor].mean_seconds : kNaN;
      if (taylor < 0) st.max_position_offset_m = kNaN;
    }
  }
  result->wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return Status::Ok();
}

std::vector<TextTable> BlockComparisonTables(const BlockComparisonOptions& options,
                                             const BlockComparisonResult& result) {
  std::vector<TextTable> tables;
  for (size_t setting = 0; setting < result.settings.size(); ++setting) {
    TextTable table;
    table.title = "Blocks of " + std::to_string(result.images_per_block) + " images (" +
                  std::to_string(options.lines) + " x " + std::to_string(options.images_per_line) +
                  "), " + result.settings[setting].Label() + ", " + std::to_string(options.trials) +
                  " blocks";
    table.header = {"solver",          "success",        "camera RMSE (mm)", "check RMSE (mm)",
                    "NEES (3 = honest)", "iterations",   "time (ms)",        "x Taylor",
                    "max offset from Taylor (mm)"};
    for (size_t s = 0; s < result.solver_names.size(); ++s) {
      const BlockSolverStatistics& st = result.statistics[setting][s];
      table.rows.push_back(
          {result.solver_names[s], std::to_string(st.successes) + "/" + std::to_string(st.trials),
           ReportFixed(1e3 * st.camera_rmse_m, 2), ReportFixed(1e3 * st.check_rmse_m, 2),
           ReportFixed(st.mean_nees, 2) +
               (st.nees_count > 0 && !st.nees_interval_95.Contains(st.mean_nees)
                    ? " (outside " + ReportFixed(st.nees_interval_95.lower, 2) + "-" +
                          ReportFixed(st.nees_interval_95.upper, 2) + ")"
                    : ""),
           ReportFixed(st.mean_iterations, 1), ReportFixed(1e3 * st.mean_seconds, 1),
           ReportFixed(st.time_ratio_to_taylor, 2),
           ReportFixed(1e3 * st.max_position_offset_m, 4)});
      for (const std::string& failure : st.failures)
        table.notes.push_back(result.solver_names[s] + " failed: " + failure);
    }
    tables.push_back(std::move(table));
  }
  return tables;
}

std::string BlockComparisonCsv(const BlockComparisonResult& result) {
  std::string csv =
      "Axis,NoisePx,TieBlunders,TiePoints,GnssSigmaM,Solver,Trials,Successes,CameraRmseM,"
      "CheckRmseM,MeanNees,NeesLow95,NeesHigh95,MeanIterations,MeanSeconds,TimeRatioToTaylor,"
      "MaxOffsetFromTaylorM\n";
  char line[1024];
  for (size_t setting = 0; setting < result.settings.size(); ++setting) {
    const BlockSetting& b = result.settings[setting];
    for (size_t s = 0; s < result.solver_names.size(); ++s) {
      const BlockSolverStatistics& st = result.statistics[setting][s];
      std::snprintf(line, sizeof(line),
                    "%s,%.17g,%d,%lld,%.17g,%s,%d,%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,"
                    "%.17g\n",
                    b.axis.c_str(), b.noise_px, b.tie_blunders, b.tie_points, b.gnss_sigma_m,
                    result.solver_names[s].c_str(), st.trials, st.successes, st.camera_rmse_m,
                    st.check_rmse_m, st.mean_nees, st.nees_interval_95.lower,
                    st.nees_interval_95.upper, st.mean_iterations, st.mean_seconds,
                    st.time_ratio_to_taylor, st.max_position_offset_m);
      csv += line;
    }
  }
  return csv;
}

std::string BlockComparisonHtml(const BlockComparisonOptions& options,
                                const BlockComparisonResult& result,
                                const std::string& command_line) {
  // Solvers within this fraction of the best camera RMSE tie: with a few blocks per setting the
  // RMSE itself is uncertain by several per cent (unitless).
  constexpr double kTieFraction = 0.05;
  std::ostringstream html;
  html << HtmlPageOpen("photopose compare: blocks", "Which block solver to use");
  // The verdict from the baseline setting.
  html << "<h2>Verdict</h2>\n";
  if (!result.statistics.empty()) {
    const std::vector<BlockSolverStatistics>& base = result.statistics[0];
    std::vector<double> rmse, seconds;
    int most = 0;
    for (const BlockSolverStatistics& st : base) most = std::max(most, st.successes);
    for (const BlockSolverStatistics& st : base) {
      rmse.push_back(st.successes == most && most > 0 ? st.camera_rmse_m : std::nan(""));
      seconds.push_back(st.mean_seconds);
    }
    const std::vector<size_t> tied = TiedBest(rmse, kTieFraction);
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
            "by up to " + FormatLengthWithUnit(st.max_position_offset_m) +
            " from the corrected linearisation in these blocks (camera RMSE " +
            FormatLengthWithUnit(st.camera_rmse_m) + " against the truth).");
    }
    if (tied.empty()) {
      html << "<div class=\"verdict bad\"><b>No solver adjusted a block at the baseline.</b>";
    } else {
      size_t fastest = tied.front();
      for (const size_t k : tied)
        if (seconds[k] < seconds[fastest]) fastest = k;
      html << "<div class=\"verdict " << (findings.empty() ? "good" : "note") << "\"><b>Use "
           << HtmlEscape(result.solver_names[fastest]) << ".</b> At the baseline ("
           << HtmlEscape(result.settings[0].Label()) << ") ";
      for (size_t k = 0; k < tied.size(); ++k)
        html << (k == 0 ? "" : (k + 1 == tied.size() ? " and " : ", ")) << "<b>"
             << HtmlEscape(result.solver_names[tied[k]]) << "</b>";
      html << (tied.size() > 1 ? " tie for the most accurate camera positions (RMSE within " +
                                     FormatUnitless(100.0 * kTieFraction, 0) + " % of "
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
  }
  html << "<h2>Glossary</h2>\n" << ComparisonGlossaryHtml()
       << "<ul class=\"notes\">\n"
       << "<li>Every solver adjusts the same simulated block from the same perturbed start "
          "(core/simulation/synthetic_block.h), with the stated accuracies equal to the true "
          "noise and the default rejection of marks beyond 4.5 sigma.</li>\n"
       << "<li>Camera RMSE: per axis, over every image of the successful blocks, of the adjusted "
          "centre minus the true one. Check RMSE: the check points intersected from the adjusted "
          "images against their true positions.</li>\n"
       << "<li>NEES here: of the camera centres (3 degrees of freedom; 3 when the reported "
          "covariance is honest), with its 95 % interval.</li>\n"
       << "<li>Time: one adjustment, single-threaded, including its statistics; x Taylor: the "
          "ratio to the corrected Taylor solver in the same run.</li>\n</ul>\n";
  // Small multiples: camera RMSE by solver, one panel per setting.
  html << "<h2>Camera accuracy per setting</h2>\n<div class=\"plots\">\n";
  for (size_t setting = 0; setting < result.settings.size(); ++setting) {
    BarPlot bars;
    bars.title = result.settings[setting].Label();
    bars.value_label = "camera RMSE (mm)";
    for (size_t s = 0; s < result.solver_names.size(); ++s) {
      const BlockSolverStatistics& st = result.statistics[setting][s];
      bars.labels.push_back(result.solver_names[s]);
      bars.values.push_back(st.successes > 0 ? 1e3 * st.camera_rmse_m : std::nan(""));
    }
    html << RenderBarPlotSvg(bars) << "\n";
  }
  html << "</div>\n<h2>Tables</h2>\n";
  for (const TextTable& table : BlockComparisonTables(options, result))
    html << RenderHtmlTable(table) << "\n";
  html << "<p>" << FormatCount(static_cast<long long>(result.settings.size() * options.trials),
                               "block")
       << " in " << FormatSignificant(result.wall_seconds, 3) << " s.</p>\n"
       << HtmlPageClose();
  return html.str();
}

Status RunBlockDatasetComparison(const BlockDatasetOptions& options, const Block& block,
                                 BlockDatasetResult* result) {
  *result = BlockDatasetResult();
  if (options.solvers.empty()) return Status::Error("no solver");
  result->num_images = static_cast<int>(block.images.size());
  result->num_points = static_cast<int>(block.points.size());
  result->num_marks = static_cast<int>(block.marks.size());
  std::vector<std::vector<Eigen::Vector3d>> centres(options.solvers.size());
  int reference = -1, taylor = -1;
  for (size_t s = 0; s < options.solvers.size(); ++s) {
    const BlockSolverVariant& variant = options.solvers[s];
    BlockDatasetSolverSummary summary;
    summary.name = variant.Name();
    Block copy = block;
    BundleAdjustmentOptions adjustment;
    adjustment.solver.num_threads = options.num_threads;
    adjustment.solver.jacobian = variant.jacobian;
    adjustment.robustness.tie_loss = variant.loss;
    adjustment.statistics.observation_diagnostics = false;
    BundleAdjustmentResult adjusted;
    const Clock::time_point begin = Clock::now();
    const Status status = BundleAdjustWithSolver(variant.solver, adjustment,
                                                 BundleAdjustmentConfig(), &copy, &adjusted);
    summary.seconds = std::chrono::duration<double>(Clock::now() - begin).count();
    summary.iterations = adjusted.summary.iterations;
    if (!status.ok()) {
      summary.message = status.message();
    } else if (!adjusted.summary.IsSolutionUsable()) {
      summary.message = adjusted.summary.message;
    } else {
      summary.success = true;
      summary.sigma0 = adjusted.summary.sigma0;
      summary.num_check_points = adjusted.num_check_points;
      summary.check_rmse_m = adjusted.num_check_points > 0 ? adjusted.check_rmse_total_m : kNaN;
      for (const BlockImage& image : copy.images) centres[s].push_back(image.eo->center_in_ground());
      if (reference < 0 && variant.solver == PoseSolver::kCeres) reference = static_cast<int>(s);
      if (variant.solver == PoseSolver::kTaylor) taylor = static_cast<int>(s);
    }
    result->solvers.push_back(summary);
  }
  if (reference < 0) {
    for (size_t s = 0; s < options.solvers.size() && reference < 0; ++s)
      if (result->solvers[s].success) reference = static_cast<int>(s);
  }
  result->reference = reference >= 0 ? result->solvers[reference].name : "";
  for (size_t s = 0; s < result->solvers.size(); ++s) {
    BlockDatasetSolverSummary& summary = result->solvers[s];
    summary.time_ratio_to_taylor =
        taylor >= 0 ? summary.seconds / result->solvers[taylor].seconds : kNaN;
    if (!summary.success || reference < 0) {
      summary.offset_rms_m = summary.offset_max_m = kNaN;
      continue;
    }
    double ssq = 0.0;
    for (size_t i = 0; i < centres[s].size(); ++i) {
      const double d = (centres[s][i] - centres[reference][i]).norm();
      ssq += d * d;
      summary.offset_max_m = std::max(summary.offset_max_m, d);
    }
    summary.offset_rms_m = centres[s].empty() ? kNaN : std::sqrt(ssq / (3.0 * centres[s].size()));
  }
  return Status::Ok();
}

TextTable BlockDatasetTable(const BlockDatasetResult& result) {
  TextTable table;
  table.title = "The block (" + std::to_string(result.num_images) + " images, " +
                std::to_string(result.num_points) + " points, " +
                std::to_string(result.num_marks) + " marks): every solver from the same start; "
                "offsets from " + (result.reference.empty() ? "no reference" : result.reference);
  table.header = {"solver", "result", "offset RMS (mm)", "offset max (mm)", "check RMSE (mm)",
                  "sigma0", "iterations", "time (ms)", "x Taylor"};
  for (const BlockDatasetSolverSummary& s : result.solvers) {
    table.rows.push_back(
        {s.name, s.success ? "converged" : "failed", ReportFixed(1e3 * s.offset_rms_m, 4),
         ReportFixed(1e3 * s.offset_max_m, 4), ReportFixed(1e3 * s.check_rmse_m, 2),
         ReportFixed(s.sigma0, 4), std::to_string(s.iterations), ReportFixed(1e3 * s.seconds, 1),
         ReportFixed(s.time_ratio_to_taylor, 2)});
    if (!s.success) table.notes.push_back(s.name + ": " + s.message);
  }
  return table;
}

std::string BlockDatasetCsv(const BlockDatasetResult& result) {
  std::string csv =
      "Solver,Success,OffsetRmsM,OffsetMaxM,CheckRmseM,NumCheckPoints,Sigma0,Iterations,Seconds,"
      "TimeRatioToTaylor\n";
  char line[512];
  for (const BlockDatasetSolverSummary& s : result.solvers) {
    std::snprintf(line, sizeof(line), "%s,%d,%.17g,%.17g,%.17g,%d,%.17g,%d,%.17g,%.17g\n",
                  s.name.c_str(), s.success ? 1 : 0, s.offset_rms_m, s.offset_max_m,
                  s.check_rmse_m, s.num_check_points, s.sigma0, s.iterations, s.seconds,
                  s.time_ratio_to_taylor);
    csv += line;
  }
  return csv;
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
