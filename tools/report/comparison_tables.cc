#include "tools/report/comparison_tables.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "tools/report/html_kit.h"

namespace photopose::cli {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();


std::string Format(const char* format, double value) {
  if (!std::isfinite(value)) return "-";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

// Three significant digits in plain notation (times in microseconds, ratios): never an
// exponent; "-" when not finite.
std::string Sig(double value) {
  if (!std::isfinite(value)) return "-";
  return FormatSignificant(value, 3);
}

std::string Percent(double fraction) { return Format("%.0f%%", 100.0 * fraction); }

std::string Full(double value) {
  if (std::isnan(value)) return "";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.12g", value);
  return buffer;
}

std::string Microseconds(double seconds) { return Sig(seconds * 1e6); }

// A cell of a table under construction: text as it stands, or a value of its column's kind.
struct Cell {
  std::string text;
  double value = kNaN;
  bool numeric = false;
};
Cell Text(std::string text) { return {std::move(text), kNaN, false}; }
Cell Value(double value) { return {"", value, true}; }

// A column: its name and, for a column of values, their kind (core/units.h FormatInOneUnit: "m"
// lengths in mm, cm or m; "deg" angle errors in arc seconds; "px"; "" unitless, two decimals).
struct Column {
  std::string name;
  std::string kind;  // empty: a column of text (or of values formatted before)
  bool values = false;
};
Column TextColumn(std::string name) { return {std::move(name), "", false}; }
Column ValueColumn(std::string name, std::string kind) {
  return {std::move(name), std::move(kind), true};
}

// The table's header and rows: every column of values in the one unit FormatInOneUnit picks for
// it (from its largest magnitude), named in its header ("pos RMSE (cm)"); a value cell that is
// not finite prints "-".
void FillTable(const std::vector<Column>& columns, const std::vector<std::vector<Cell>>& cells,
               TextTable* table) {
  table->header.clear();
  table->rows.assign(cells.size(), std::vector<std::string>(columns.size()));
  for (size_t c = 0; c < columns.size(); ++c) {
    std::vector<double> values;
    for (const auto& row : cells)
      if (c < row.size() && row[c].numeric) values.push_back(row[c].value);
    const ValuesInOneUnit in_one =
        FormatInOneUnit(values, columns[c].kind.empty() ? "unitless" : columns[c].kind);
    const bool named = columns[c].values && !columns[c].kind.empty();
    table->header.push_back(named ? columns[c].name + " (" + in_one.unit + ")" : columns[c].name);
    size_t k = 0;
    for (size_t r = 0; r < cells.size(); ++r) {
      if (c >= cells[r].size()) continue;
      const Cell& cell = cells[r][c];
      if (!cell.numeric) {
        table->rows[r][c] = cell.text;
        continue;
      }
      const std::string& text = in_one.texts[k++];
      table->rows[r][c] = text == "n/a" ? "-" : text;
    }
  }
}

// An angle in arc seconds as the degrees FormatInOneUnit's "deg" kind takes.
double ArcsecondsToDegrees(double arcsec) { return arcsec / 3600.0; }

std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

}  // namespace

// ------------------------------------------------------------------ rendering

std::string SweepSettingTitle(const SweepSetting& s, int trials, int images) {
  return std::string(EnumName(s.scenario)) + ": noise " + FormatSignificant(s.noise_px, 4) +
         " px, outliers " + FormatSignificant(100.0 * s.outlier_fraction, 4) + "%, " +
         FormatCount(s.control_points, "control point") + ", initial error +-" +
         FormatScaledLength(s.initial_error.position_m) + " +-" +
         FormatScaledAngle(s.initial_error.angle_deg) + " (" + s.axis + "; " +
         FormatCount(trials, "trial") + " x " + FormatCount(images, "image") + ")";
}

std::vector<std::string> MonteCarloNotes(const MonteCarloOptions& options) {
  const std::string success =
      "success: a pose was returned and |X0 - X0_true| <= " +
      FormatSignificant(options.success_sigmas, 4) +
      " design sigmas, sigma = sqrt(trace C_pos), C = (J^T P J)^-1 at the true pose; its mean is "
      "in each table title.";
  return {
      "solved: a pose was returned; success as below. pos/rot/check/reproj RMSE are over the "
      "solved samples (rotation: angle of R_true^T R_est; check and reproj: RMS of the 2-D "
      "residual norm, reproj over uncontaminated control marks). d_ref pos, d_ref rot: RMS of the "
      "paired differences to the reference solver (taylor when compared) on the same data and "
      "start. Lengths in the unit of the column's largest value (mm below 0.1 m, cm below 10 m), "
      "angles in arc seconds.",
      success,
      "time: median wall time of one ResectImage call (statistics included) over the solved "
      "samples; refine: its refinement part; t/ref: time over the reference solver's (taylor "
      "when compared).",
      "nees: mean of e^T C^-1 e over the solved samples, e = pose error (X0 in m, seed angles in "
      "rad, wrapped), C = the solver's covariance sigma0^2 (J^T P J)^-1; its expectation with "
      "sigma0 estimated from r = 2n - 6 redundant observations is E[nees] = 6 r/(r-2). nees_ap: "
      "the same with sigma0 = 1, chi-square(6) when the covariance is honest.",
      "99% int: interval of the mean of N chi-square(6) variables, [q(0.005), q(0.995)] of "
      "chi-square(6N) / N, quantiles by numerical inversion of the regularized gamma function. "
      "cov: ok when nees_ap is inside it, HIGH (covariance too optimistic) or low. Not computed "
      "for noise 0.",
      std::string("initial values: ") +
          (options.initial == InitialValues::kApproximateFrames
               ? "the scene's approximate frames (the same for every solver)"
               : "LO-RANSAC per image, one seed per image and trial (the same for every solver)") +
          "; trial t uses scene seed " + std::to_string(options.seed) + " + t.",
  };
}

std::vector<TextTable> MonteCarloTables(const MonteCarloOptions& options,
                                        const MonteCarloResult& result) {
  std::vector<TextTable> tables;
  const size_t reference = ReferenceSolverIndex(result.solver_names);
  for (const SettingResult& setting : result.settings) {
    TextTable table;
    table.title = SweepSettingTitle(setting.setting, options.trials, setting.images_per_trial);
    double threshold = kNaN;
    if (!setting.solvers.empty()) threshold = setting.solvers.front().mean_success_threshold_m;
    table.title += ", success threshold " + FormatScaledLength(threshold);
    const std::vector<Column> columns = {
        TextColumn("solver"),         TextColumn("solved"),
        TextColumn("success"),        ValueColumn("pos RMSE", "m"),
        ValueColumn("rot RMSE", "deg"), ValueColumn("d_ref pos", "m"),
        ValueColumn("d_ref rot", "deg"), ValueColumn("check RMSE", "px"),
        ValueColumn("reproj RMSE", "px"), TextColumn("iter"),
        TextColumn("time (us)"),      TextColumn("refine (us)"),
        TextColumn("t/ref"),          ValueColumn("nees", ""),
        ValueColumn("E[nees]", ""),   ValueColumn("nees_ap", ""),
        TextColumn("99% int"),        TextColumn("cov")};
    std::vector<std::vector<Cell>> cells;
    const double reference_seconds = setting.solvers[reference].median_seconds;
    for (const SolverStatistics& s : setting.solvers) {
      const bool has_nees = s.nees_count > 0;
      std::string verdict = "-";
      if (has_nees && std::isfinite(s.mean_nees_apriori)) {
        verdict = s.nees_interval_99.Contains(s.mean_nees_apriori) ? "ok"
                  : s.mean_nees_apriori > s.nees_interval_99.upper ? "HIGH"
                                                                   : "low";
      }
      cells.push_back({
          Text(s.solver),
          Text(Percent(static_cast<double>(s.solved) / std::max(1, s.samples))),
          Text(Percent(s.success_rate)),
          Value(s.position_rmse_m),
          Value(ArcsecondsToDegrees(s.rotation_rmse_arcsec)),
          Value(s.difference_position_rmse_m),
          Value(ArcsecondsToDegrees(s.difference_rotation_rmse_arcsec)),
          Value(s.check_rmse_px),
          Value(s.reprojection_rmse_px),
          Text(Format("%.1f", s.mean_iterations)),
          Text(Microseconds(s.median_seconds)),
          Text(Microseconds(s.median_refinement_seconds)),
          Text(Format("%.2f", s.median_seconds / reference_seconds)),
          Value(has_nees ? s.mean_nees : kNaN),
          Value(has_nees ? s.expected_nees : kNaN),
          Value(has_nees ? s.mean_nees_apriori : kNaN),
          Text(has_nees ? "[" + FormatUnitless(s.nees_interval_99.lower) + ", " +
                              FormatUnitless(s.nees_interval_99.upper) + "]"
                        : "-"),
          Text(verdict),
      });
    }
    FillTable(columns, cells, &table);
    for (const SolverStatistics& s : setting.solvers) {
      std::string reasons;
      for (size_t k = 0; k < s.failure_reasons.size() && k < 2; ++k)
        reasons += (k ? "; " : "") + std::to_string(s.failure_reasons[k].second) + " x " +
                   s.failure_reasons[k].first;
      if (s.failure_reasons.size() > 2) reasons += "; ...";
      if (!reasons.empty()) table.notes.push_back("not solved, " + s.solver + ": " + reasons);
    }
    tables.push_back(table);
  }

  return tables;
}

std::string MonteCarloCsv(const MonteCarloResult& result) {
  std::ostringstream csv;
  csv << "scenario,axis,noise_px,outlier_fraction,control_points,initial_position_error_m,"
         "initial_angle_error_deg,images_per_trial,solver,samples,solved,successes,success_rate,"
         "success_threshold_m,position_rmse_m,rotation_rmse_arcsec,difference_rmse_m,"
         "difference_rmse_arcsec,check_rmse_px,"
         "reprojection_rmse_px,mean_iterations,median_time_us,median_refinement_time_us,"
         "time_ratio,mean_nees,mean_nees_apriori,expected_nees,nees_count,nees95_lower,"
         "nees95_upper,nees99_lower,nees99_upper\n";
  const size_t reference = ReferenceSolverIndex(result.solver_names);
  for (const SettingResult& setting : result.settings) {
    const SweepSetting& x = setting.setting;
    for (const SolverStatistics& s : setting.solvers) {
      csv << EnumName(x.scenario) << "," << x.axis << "," << Full(x.noise_px) << ","
          << Full(x.outlier_fraction) << "," << x.control_points << ","
          << Full(x.initial_error.position_m) << "," << Full(x.initial_error.angle_deg) << ","
          << setting.images_per_trial << "," << CsvField(s.solver) << "," << s.samples << ","
          << s.solved << "," << s.successes << "," << Full(s.success_rate) << ","
          << Full(s.mean_success_threshold_m) << "," << Full(s.position_rmse_m) << ","
          << Full(s.rotation_rmse_arcsec) << "," << Full(s.difference_position_rmse_m) << ","
          << Full(s.difference_rotation_rmse_arcsec) << "," << Full(s.check_rmse_px) << ","
          << Full(s.reprojection_rmse_px) << "," << Full(s.mean_iterations) << ","
          << Full(s.median_seconds * 1e6) << "," << Full(s.median_refinement_seconds * 1e6) << ","
          << Full(s.median_seconds / setting.solvers[reference].median_seconds) << ","
          << Full(s.mean_nees) << "," << Full(s.mean_nees_apriori) << "," << Full(s.expected_nees)
          << "," << s.nees_count << "," << Full(s.nees_interval_95.lower) << ","
          << Full(s.nees_interval_95.upper) << "," << Full(s.nees_interval_99.lower) << ","
          << Full(s.nees_interval_99.upper) << "\n";
    }
  }
  return csv.str();
}

namespace {

// The dataset comparison's table of solvers: one row per solver over every image.
TextTable DatasetSummaryTable(const DatasetComparisonResult& result) {
  const size_t reference = ReferenceSolverIndex(result.solver_names);
  const double reference_seconds = result.summaries[reference].median_seconds;
  TextTable summary;
  summary.title = "Solvers (differences to " + result.reference_solver + ")";
  std::vector<Column> columns = {
      TextColumn("solver"),          TextColumn("solved"),
      TextColumn("sigma0"),          ValueColumn("RMS", "px"),
      ValueColumn("check RMSE", "px"), TextColumn("check beyond"),
      TextColumn("iter"),            TextColumn("time (us)"),
      TextColumn("t/ref"),           TextColumn("refine (us)"),
      ValueColumn("d_ref pos", "m"), ValueColumn("d_ref rot", "deg")};
  if (result.has_reference) {
    columns.push_back(ValueColumn("d_frames pos", "m"));
    columns.push_back(ValueColumn("d_frames rot", "deg"));
  }
  std::vector<std::vector<Cell>> summary_cells;
  for (const DatasetSolverSummary& s : result.summaries) {
    std::vector<Cell> row = {
        Text(s.solver),
        Text(std::to_string(s.solved) + "/" + std::to_string(s.images)),
        Text(FormatUnitless(s.rms_sigma0, 3)),
        Value(s.rms_px),
        Value(s.check_rmse_px),
        Text(std::to_string(s.check_beyond)),
        Text(Format("%.1f", s.mean_iterations)),
        Text(Microseconds(s.median_seconds)),
        Text(Format("%.2f", s.median_seconds / reference_seconds)),
        Text(Microseconds(s.median_refinement_seconds)),
        Value(s.compared > 0 ? s.difference_position_m : kNaN),
        Value(s.compared > 0 ? ArcsecondsToDegrees(s.difference_rotation_arcsec) : kNaN)};
    if (result.has_reference) {
      row.push_back(Value(s.referenced > 0 ? s.reference_position_m : kNaN));
      row.push_back(
          Value(s.referenced > 0 ? ArcsecondsToDegrees(s.reference_rotation_arcsec) : kNaN));
    }
    summary_cells.push_back(row);
  }
  FillTable(columns, summary_cells, &summary);
  summary.notes = {
      "sigma0: RMS over images of the a-posteriori sigma0 (unitless); RMS: of the inlier residual "
      "norms; check RMSE: of the check-point residual norms within the inlier threshold, check "
      "beyond: check marks beyond it; time: median per image (RANSAC included when it ran), "
      "refine: its refinement part.",
      "d_ref pos, d_ref rot: RMS over images of |X0 - X0_" + result.reference_solver +
          "| and of the rotation angle between the two." +
          (result.has_reference ? " d_frames pos, d_frames rot: the same to the reference frames."
                                : "")};
  return summary;
}

// One row of the per-image table: an image as one solver oriented it.
std::vector<Cell> DatasetImageRow(const DatasetComparisonResult& result, const DatasetSolve& s) {
  std::vector<Cell> row = {Text(s.raster), Text(result.solver_names[s.solver]),
                           Text(s.success ? "ok" : "failed")};
  if (s.success) {
    for (int k = 0; k < 3; ++k) row.push_back(Text(FormatCoordinate(s.eo.parameters[k])));
    for (int k = 0; k < 3; ++k) row.push_back(Text(FormatDegrees(s.angles_deg[k])));
    row.push_back(Text(FormatUnitless(s.sigma0, 3)));
    row.push_back(Text(std::to_string(s.num_inliers) + "/" + std::to_string(s.num_observations)));
    row.push_back(Value(s.rms_px));
    row.push_back(Value(s.check_rmse_px));
    row.push_back(Text(std::to_string(s.num_check_beyond)));
  } else {
    for (int k = 0; k < 9; ++k) row.push_back(Text("-"));
    row.push_back(Value(kNaN));
    row.push_back(Value(kNaN));
    row.push_back(Text("-"));
  }
  row.push_back(Text(std::to_string(s.iterations)));
  row.push_back(Text(Microseconds(s.seconds)));
  row.push_back(Value(s.has_difference ? s.difference_position_m : kNaN));
  row.push_back(Value(s.has_difference ? ArcsecondsToDegrees(s.difference_rotation_arcsec) : kNaN));
  if (result.has_reference) {
    row.push_back(Value(s.has_reference ? s.reference_position_m : kNaN));
    row.push_back(Value(s.has_reference ? ArcsecondsToDegrees(s.reference_rotation_arcsec) : kNaN));
  }
  return row;
}

// The dataset comparison's per-image table: every image by every solver, failures in the notes.
TextTable DatasetImageTable(const DatasetComparisonResult& result) {
  TextTable images;
  images.title = std::string("Per image (angles in the ") + EnumName(result.rotation) +
                 " convention)";
  std::vector<Column> image_columns = {
      TextColumn("image"),     TextColumn("solver"),         TextColumn("status"),
      TextColumn("X (m)"),     TextColumn("Y (m)"),          TextColumn("Z (m)"),
      TextColumn("omega (deg)"), TextColumn("phi (deg)"),    TextColumn("kappa (deg)"),
      TextColumn("sigma0"),    TextColumn("inliers"),        ValueColumn("RMS", "px"),
      ValueColumn("check RMSE", "px"), TextColumn("check beyond"), TextColumn("iter"),
      TextColumn("time (us)"), ValueColumn("d_ref pos", "m"), ValueColumn("d_ref rot", "deg")};
  if (result.has_reference) {
    image_columns.push_back(ValueColumn("d_frames pos", "m"));
    image_columns.push_back(ValueColumn("d_frames rot", "deg"));
  }
  std::vector<std::vector<Cell>> image_cells;
  for (const DatasetSolve& s : result.solves) image_cells.push_back(DatasetImageRow(result, s));
  FillTable(image_columns, image_cells, &images);
  for (const DatasetSolve& s : result.solves)
    if (!s.success)
      images.notes.push_back(s.raster + " " + result.solver_names[s.solver] + ": " + s.message);
  return images;
}

}  // namespace

std::vector<TextTable> DatasetTables(const DatasetComparisonResult& result) {
  return {DatasetSummaryTable(result), DatasetImageTable(result)};
}

std::string DatasetCsv(const DatasetComparisonResult& result) {
  std::ostringstream csv;
  csv << "Raster,Solver,Success,Message,X,Y,Z,Omega,Phi,Kappa,Convention,SigmaX,SigmaY,SigmaZ,"
         "SigmaOmegaSeed,SigmaPhiSeed,SigmaKappaSeed,Sigma0,NumObservations,NumInliers,RmsPx,"
         "MaxPx,CheckRmsePx,NumCheck,NumCheckBeyond,Iterations,TimeUs,RefinementTimeUs,"
         "DiffPositionM,DiffRotationArcsec,"
         "RefPositionM,RefRotationArcsec\n";
  for (const DatasetSolve& s : result.solves) {
    csv << CsvField(s.raster) << "," << CsvField(result.solver_names[s.solver]) << ","
        << (s.success ? 1 : 0) << "," << CsvField(s.message) << ",";
    if (s.success) {
      for (int k = 0; k < 3; ++k) csv << Full(s.eo.parameters[k]) << ",";
      for (int k = 0; k < 3; ++k) csv << Full(s.angles_deg[k]) << ",";
      csv << EnumName(result.rotation) << ",";
      for (int k = 0; k < 3; ++k) csv << Full(s.standard_deviations[k]) << ",";
      for (int k = 3; k < 6; ++k) csv << Full(RadiansToDegrees(s.standard_deviations[k])) << ",";
      csv << Full(s.sigma0) << "," << s.num_observations << "," << s.num_inliers << ","
          << Full(s.rms_px) << "," << Full(s.max_px) << "," << Full(s.check_rmse_px) << ","
          << s.num_check << "," << s.num_check_beyond << ",";
    } else {
      csv << ",,,,,,,,,,,,,," << s.num_observations << ",,,,,,,";
    }
    csv << s.iterations << "," << Full(s.seconds * 1e6) << "," << Full(s.refinement_seconds * 1e6)
        << "," << (s.has_difference ? Full(s.difference_position_m) : "") << ","
        << (s.has_difference ? Full(s.difference_rotation_arcsec) : "") << ","
        << (s.has_reference ? Full(s.reference_position_m) : "") << ","
        << (s.has_reference ? Full(s.reference_rotation_arcsec) : "") << "\n";
  }
  return csv.str();
}

std::string WrapText(const std::string& text, const std::string& first_indent,
                     const std::string& indent, size_t width) {
  std::string out, line = first_indent;
  bool line_empty = true;
  std::istringstream words(text);
  std::string word;
  while (words >> word) {
    if (!line_empty && line.size() + 1 + word.size() > width) {
      out += line + "\n";
      line = indent;
      line_empty = true;
    }
    line += (line_empty ? "" : " ") + word;
    line_empty = false;
  }
  if (!line_empty) out += line + "\n";
  return out;
}

std::string RenderText(const TextTable& table) {
  const size_t num_columns = table.header.size();
  std::vector<size_t> width(num_columns, 0);
  for (size_t c = 0; c < num_columns; ++c) width[c] = table.header[c].size();
  for (const auto& row : table.rows)
    for (size_t c = 0; c < row.size() && c < width.size(); ++c)
      width[c] = std::max(width[c], row[c].size());
  // The first columns name things (left-aligned, repeated in every block); the rest are numbers
  // (right-aligned), in as many blocks of columns under one another as kConsoleWidth needs.
  const size_t num_keys = std::min<size_t>(num_columns, table.header.empty()           ? 0
                                                         : table.header[0] == "image" ? 2
                                                                                       : 1);
  size_t key_width = 0;
  for (size_t c = 0; c < num_keys; ++c) key_width += width[c] + (c == 0 ? 0 : 2);
  std::vector<std::vector<size_t>> blocks;
  for (size_t c = num_keys; c < num_columns; ++c) {
    size_t used = key_width;
    if (!blocks.empty())
      for (size_t k : blocks.back()) used += width[k] + 2;
    if (blocks.empty() || used + 2 + width[c] > kConsoleWidth) blocks.emplace_back();
    blocks.back().push_back(c);
  }
  if (blocks.empty()) blocks.emplace_back();
  std::ostringstream out;
  if (!table.title.empty()) out << WrapText(table.title, "", "  ", kConsoleWidth);
  for (size_t b = 0; b < blocks.size(); ++b) {
    std::vector<size_t> columns;
    for (size_t c = 0; c < num_keys; ++c) columns.push_back(c);
    columns.insert(columns.end(), blocks[b].begin(), blocks[b].end());
    auto line = [&](const std::vector<std::string>& cells) {
      std::string text;
      for (size_t k = 0; k < columns.size(); ++k) {
        const size_t c = columns[k];
        const std::string cell = c < cells.size() ? cells[c] : "";
        const std::string pad(width[c] - std::min(width[c], cell.size()), ' ');
        text += (k == 0 ? "" : "  ") + (c < num_keys ? cell + pad : pad + cell);
      }
      while (!text.empty() && text.back() == ' ') text.pop_back();
      out << text << "\n";
    };
    if (b > 0) out << "\n";
    line(table.header);
    size_t total = 0;
    for (size_t k = 0; k < columns.size(); ++k) total += width[columns[k]] + (k == 0 ? 0 : 2);
    out << std::string(total, '-') << "\n";
    for (const auto& row : table.rows) line(row);
  }
  for (const std::string& note : table.notes) out << WrapText(note, "  ", "    ", kConsoleWidth);
  return out.str();
}

std::string RenderMarkdown(const TextTable& table) {
  std::ostringstream out;
  auto escape = [](const std::string& cell) {
    std::string text;
    for (char c : cell) {
      if (c == '|') text += '\\';
      text += c;
    }
    return text;
  };
  if (!table.title.empty()) out << "**" << escape(table.title) << "**\n\n";
  out << "|";
  for (const auto& h : table.header) out << " " << escape(h) << " |";
  out << "\n|";
  for (size_t c = 0; c < table.header.size(); ++c) out << (c == 0 ? "---|" : "---:|");
  out << "\n";
  for (const auto& row : table.rows) {
    out << "|";
    for (const auto& cell : row) out << " " << escape(cell) << " |";
    out << "\n";
  }
  if (!table.notes.empty()) {
    out << "\n";
    for (const std::string& note : table.notes) out << "- " << escape(note) << "\n";
  }
  return out.str();
}

// ------------------------------------------------------------------ block comparisons

std::vector<TextTable> BlockComparisonTables(const BlockComparisonOptions& options,
                                             const BlockComparisonResult& result) {
  std::vector<TextTable> tables;
  for (size_t setting = 0; setting < result.settings.size(); ++setting) {
    TextTable table;
    table.title = "Blocks of " + std::to_string(result.images_per_block) + " images (" +
                  std::to_string(options.lines) + " x " + std::to_string(options.images_per_line) +
                  "), " + result.settings[setting].Label() + ", " + std::to_string(options.trials) +
                  " blocks";
    const std::vector<Column> columns = {
        TextColumn("solver"),           TextColumn("success"),
        ValueColumn("camera RMSE", "m"), ValueColumn("check RMSE", "m"),
        TextColumn("NEES (3 = honest)"), TextColumn("iterations"),
        TextColumn("time (ms)"),        TextColumn("x Taylor"),
        ValueColumn("max offset from Taylor", "m")};
    std::vector<std::vector<Cell>> cells;
    for (size_t s = 0; s < result.solver_names.size(); ++s) {
      const BlockSolverStatistics& st = result.statistics[setting][s];
      cells.push_back(
          {Text(result.solver_names[s]),
           Text(std::to_string(st.successes) + "/" + std::to_string(st.trials)),
           Value(st.camera_rmse_m), Value(st.check_rmse_m),
           Text(FormatUnitless(st.mean_nees) +
                (st.nees_count > 0 && !st.nees_interval_95.Contains(st.mean_nees)
                     ? " (outside " + FormatUnitless(st.nees_interval_95.lower) + "-" +
                           FormatUnitless(st.nees_interval_95.upper) + ")"
                     : "")),
           Text(ReportFixed(st.mean_iterations, 1)), Text(ReportFixed(1e3 * st.mean_seconds, 1)),
           Text(FormatUnitless(st.time_ratio_to_taylor)), Value(st.max_position_offset_m)});
      for (const std::string& failure : st.failures)
        table.notes.push_back(result.solver_names[s] + " failed: " + failure);
    }
    FillTable(columns, cells, &table);
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

TextTable BlockDatasetTable(const BlockDatasetResult& result) {
  TextTable table;
  table.title = "The block (" + std::to_string(result.num_images) + " images, " +
                std::to_string(result.num_points) + " points, " +
                std::to_string(result.num_marks) + " marks): every solver from the same start; "
                "offsets from " + (result.reference.empty() ? "no reference" : result.reference);
  const std::vector<Column> columns = {
      TextColumn("solver"),          TextColumn("result"),
      ValueColumn("offset RMS", "m"), ValueColumn("offset max", "m"),
      ValueColumn("check RMSE", "m"), TextColumn("sigma0"),
      TextColumn("iterations"),      TextColumn("time (ms)"),
      TextColumn("x Taylor")};
  std::vector<std::vector<Cell>> cells;
  for (const BlockDatasetSolverSummary& s : result.solvers) {
    cells.push_back({Text(s.name), Text(s.success ? "converged" : "failed"),
                     Value(s.offset_rms_m), Value(s.offset_max_m), Value(s.check_rmse_m),
                     Text(FormatUnitless(s.sigma0, 3)), Text(std::to_string(s.iterations)),
                     Text(ReportFixed(1e3 * s.seconds, 1)),
                     Text(FormatUnitless(s.time_ratio_to_taylor))});
    if (!s.success) table.notes.push_back(s.name + ": " + s.message);
  }
  FillTable(columns, cells, &table);
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

}  // namespace photopose::cli
