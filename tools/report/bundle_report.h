#pragma once
// What `photopose bundle` writes about an adjustment (docs/formats.md, "Output of photopose
// bundle"): the JSON report, the self-contained HTML page, the points table, the frames records
// and the console summary. Everything here reads a block and its BundleAdjustmentResult; nothing
// adjusts.

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/pixel_rows.h"
#include "core/rotation.h"
#include "core/units.h"
#include "core/io/tables.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/georeference/georeference.h"

namespace photopose::cli {

// How the run was asked for, for the report.
struct BundleReportContext {
  std::string command_line;
  RotationConvention rotation = RotationConvention::kSeed;  // of the angles reported
  std::vector<std::string> inputs;                          // files read
  std::vector<std::string> outputs;                         // files written (besides the report)
  std::string input_kind;  // "tables", "colmap" or "bal"
  // The tables' pixel rows as read (--pixel_rows_up); a model's and BAL's are their readers'.
  PixelRows pixel_rows = PixelRows::kDown;
  BundleAdjustmentOptions options;
  BundleAdjustmentConfig config;  // what was held constant or estimated (e.g. the lever arm)
  std::vector<std::string> calibrate;  // --calibrate names
  const BundleCrossValidationResult* cross_validation = nullptr;  // when run
  int num_images_initialized = 0;      // images oriented by the initialisation
  double read_seconds = 0.0;            // reading the inputs into the block (s)
  double initialization_seconds = 0.0;  // resection and intersection of what had no start (s)
  const GeoreferenceResult* georeference = nullptr;  // a georeferenced model (its section)
};

// An observation of a group in words ("mark of 'P1' in 'img_2'", "control point 'C3'", "attitude
// of 'img_4'") and the name of its axis (x, y; X, Y, Z; omega, phi, kappa), for every report.
std::string BundleItemName(const Block& block, BundleGroup group, int item);
const char* BundleAxisName(BundleGroup group, int axis);

// Variance component estimation (--estimate_accuracies) on a group whose estimated accuracy is
// more than kGrossErrorFactor times its stated one (AbsorbsGrossErrors): gross errors are far
// likelier than a misstated accuracy, and the estimation absorbed them (it rescales every
// observation of the group, so sigma0 ends near 1 and does not show them). `photopose bundle`
// then searches for them as it does when sigma0 stays above 3 (data snooping); GrossErrorsAbsorbed
// states, in words, what is still so after that search, with the remedy. Empty otherwise. The
// console (unit_text kAscii) and the HTML page (kUtf8: "µm") state it.
constexpr double kGrossErrorFactor = 3.0;
bool AbsorbsGrossErrors(const BundleGroupStatistics& group);
std::string GrossErrorsAbsorbed(const BundleGroupStatistics& group, UnitText unit_text);

// The weakly determined parameters of a result (BundleAdjustmentResult::weakly_determined) in
// words, the worst five named, with what it means; empty when there are none. The console and the
// HTML page state it.
std::string WeaklyDeterminedWarning(const BundleAdjustmentResult& result);

// Chi-square(3) level above which a check point's error e^T C^-1 e stands out (0.1 % of honest
// cases): the one rule of the page's verdict, its table notes and the console's warnings.
inline constexpr double kCheckPointLevel = 0.999;
// A group's figures and whether its stated accuracy is shown per axis: the library's
// FormatGroupFigures and StatedPerAxis (solvers/bundle/bundle_adjustment.h), which FullReport uses
// too.
// Whether a group's over-fitting was judged: false for a weighted prior group (control points,
// camera positions, attitudes) without a redundancy share (the statistics were not computed,
// --statistics=none), whose `overfit` false is then no verdict (the library flags nothing without
// a share: an RMS well below the stated accuracy may be over-fitting or a loose accuracy): the
// JSON writes its `overfit` as null, the page says "not judged", the console line says so; mark
// groups and fixed groups are judged (never over-fitted).
bool OverfitJudged(const BundleGroupStatistics& g);

// A check point's normalized error e^T C^-1 e, C the covariance of the error: the intersection's
// plus the surveyed coordinates' (SurveyedPointErrorCovariance, solvers/bundle/check_points.h;
// `default_marker_m` the accuracy of a point that states none). Chi-square(3) when both are
// honest; NaN without an error or a covariance, or with the intersection's covariance alone
// (BundlePointResult::covariance_complete false: no statistics, the images taken as error-free).
double CheckPointNormalizedError(const BlockPoint& point, const BundlePointResult& r,
                                 double default_marker_m);
// The standard deviation of a check point's error, sqrt(trace C) with C as above (m); NaN as above.
double CheckPointErrorSigma(const BlockPoint& point, const BundlePointResult& r,
                            double default_marker_m);
// Each check point whose error stands out (above the kCheckPointLevel quantile), in words: "P7
// misses by 12.3 cm where its sigma is 1.80 cm (e^T C^-1 e = 46.8 > 16.3): check its surveyed
// coordinates and its marks".
std::vector<std::string> CheckPointsOutOfTolerance(const Block& block,
                                                   const BundleAdjustmentResult& result,
                                                   double default_marker_m);
// Control points without a stated accuracy whose coordinates data snooping removed, in words
// (empty when none): the w-test judged them against the default `default_marker_m` (m), which
// may only be a wrong assumption, not a blunder.
std::string ControlRemovedOnAssumedAccuracy(const Block& block,
                                            const BundleAdjustmentResult& result,
                                            double default_marker_m);

// The JSON report; every key is documented in docs/formats.md.
nlohmann::json BundleReportJson(const Block& block, const BundleAdjustmentResult& result,
                                const BundleReportContext& context);

// A self-contained HTML page (inline CSS and SVG, no script): the over-fitting verdict and the
// check RMSE at the top; cameras and points in plan view with error ellipses and control/check
// residual vectors (exaggerated, the scale stated); residual histograms per group; the control
// and check tables, calibration, diagnostics.
std::string BundleReportHtml(const Block& block, const BundleAdjustmentResult& result,
                             const BundleReportContext& context);
// The terms of the bundle report (sigma0, redundancy numbers, w-test, data snooping, delta0, ...)
// as a definition list: the last part of BundleReportHtml's diagnostics.
std::string BundleGlossaryHtml();

// The points table: PointID, X, Y, Z (the estimate of every point: adjusted tie and control
// points, intersected check points; empty for a check point that could not be intersected),
// SigmaX, SigmaY, SigmaZ (m), Role, NumObservations, SurveyedX, SurveyedY, SurveyedZ (control and
// check points, as surveyed), ErrorX, ErrorY, ErrorZ (m; estimate - surveyed), SRS (the CRS of
// X, Y, Z and Surveyed*, as the frames table's SRS: BundlePointsSrs). With `georeference` the
// coordinates are in its output CRS and the sigmas and errors along its level axes (m); without,
// in the block's ground frame.
Status FormatBundlePoints(const Block& block, const BundleAdjustmentResult& result,
                          const GeoreferenceResult* georeference, std::string* csv);
// The points table's SRS: the output CRS of a georeferenced model as PROJ was given it (the frames
// table's SRS, GeoreferencedFrames); else the block's CRS as read; else the SRS its cameras' table
// rows name when they all name the same one (a frames row's SRS falls back the other way: its
// camera's, else the block's, BundleFrames); else empty.
std::string BundlePointsSrs(const Block& block, const GeoreferenceResult* georeference);

// The frames records of the adjusted images: eo, covariance, Sigma0, NumObservations (marks
// used) and RmsResidual (their RMS, in the marks' unit) as extra columns.
std::vector<FrameRecord> BundleFrames(const Block& block, const BundleAdjustmentResult& result);

// The lines printed at the end of a run: the result, each group's verdict, and one line of advice
// per finding (over-fitted priors, estimated accuracies, blunders, points that stand out).
std::vector<std::string> BundleConsoleLines(const Block& block, const BundleAdjustmentResult& result,
                                            const BundleReportContext& context);

}  // namespace photopose::cli
