#pragma once
// Numbers a surveyor reads: the one rule for printing lengths, angles, image measurements and
// unitless figures in reports (the bundle adjustment's FullReport, the console tables of
// `photopose compare`, every HTML page of tools/report). Fixed units per quantity (mm, cm or m for
// errors and sigmas, um for film, px for marks, degrees and arc seconds for angles), fixed
// decimals per unit, never an exponent; "n/a" when a value is not finite.
//
// Lengths that are errors or sigmas take the unit their magnitude calls for; values read together
// (a table column, the figures of one line) share one unit, LengthUnitFor of their largest
// magnitude, and name it once (in the header, or after each figure).

#include <string>
#include <vector>

#include "core/camera_models.h"
#include "core/enum_names.h"

namespace photopose {

// `value` with `digits` decimals; "n/a" when it is not finite.
std::string ReportFixed(double value, int digits);

enum class LengthUnit { kMillimetre, kCentimetre, kMetre };
inline constexpr EnumNameEntry<LengthUnit> kLengthUnitNames[] = {
    {LengthUnit::kMillimetre, "mm"}, {LengthUnit::kCentimetre, "cm"}, {LengthUnit::kMetre, "m"}};
constexpr EnumNameTable<LengthUnit> EnumNames(LengthUnit) {
  return EnumNameTable<LengthUnit>(kLengthUnitNames);
}
// mm below 0.1 m, cm below 10 m, m from there (of the largest magnitude, m).
LengthUnit LengthUnitFor(double largest_magnitude_m);
// The largest finite magnitude of `values` (0 when there is none): what LengthUnitFor takes for a
// column.
double LargestMagnitude(const std::vector<double>& values);
const char* LengthUnitName(LengthUnit unit);  // "mm", "cm", "m": EnumName(unit)
// The value (m) in `unit` as a number (for plots).
double LengthIn(double value_m, LengthUnit unit);
// The value (m) in `unit` without the unit: mm and cm with one decimal, m with three.
std::string FormatLength(double value_m, LengthUnit unit);
// The value (m) in the unit its own magnitude calls for, with the unit: "6.9 mm", "1.24 m".
std::string FormatLengthWithUnit(double value_m);
// Lengths (m) printed side by side on one line, in one unit: LengthUnitFor of their largest
// finite magnitude, each with the unit ("27.9 cm", "1000.0 cm"); "n/a" when not finite.
std::vector<std::string> FormatLengthsWithUnit(const std::vector<double>& values_m);
// A ground coordinate or a camera position (m) to the millimetre: "1234.567".
std::string FormatCoordinate(double value_m);
// Image measurements: pixels (px) and film coordinates (um), two decimals.
std::string FormatPixels(double value_px);
std::string FormatFilm(double value_um);

// Values of one kind read together (a table column, the columns of a row, the figures of one
// line) in one unit for all of them, and that unit's name. The kind is a group's unit
// (BundleGroupStatistics::unit) or a table column's quantity: marks in "px", "um", or "sigma" for a
// group mixing pixel and film marks (solvers/bundle/bundle_statistics.cc), two decimals; "m" in
// mm, cm or m (LengthUnitFor of the largest finite magnitude, FormatLength); "deg" (an error or a
// sigma of an angle) in arc seconds, one decimal ("arcsec"). Any other kind keeps its values with
// two decimals and names the kind as the unit.
struct ValuesInOneUnit {
  std::string unit;                // "px", "um", "sigma", "mm", "cm", "m" or "arcsec"
  std::vector<std::string> texts;  // one per value, without the unit; "n/a" when not finite
};
ValuesInOneUnit FormatInOneUnit(const std::vector<double>& values, const std::string& kind);
// The same with the unit after each value ("5.0 mm", "0.50 px", "36.0 arcsec"; "n/a" alone): the
// figures of one line (stated, RMS, estimated).
std::vector<std::string> FormatMarkValues(const std::vector<double>& values,
                                          const std::string& kind);
// One value: FormatMarkValues({value}, kind).
std::string FormatMarkValue(double value, const std::string& kind);

// The figures of one row read together (one group of an adjustment: its stated, RMS and
// estimated accuracy) in one unit chosen from the row's own magnitudes, so that every value shown
// has at least two significant digits, at most kMaxRowDecimals decimals and never an exponent.
// Lengths ("m"): the unit of the largest (LengthUnitFor), a smaller one (cm, then mm) when the
// smallest would need more decimals in it (10 m beside 0.04 mm); other kinds in their unit as
// FormatInOneUnit (px, um, sigma, arc seconds). Decimals: those that give the smallest non-zero
// magnitude two significant digits, at least one (two for marks), at most kMaxRowDecimals:
// {0.0005, 0.0021} m reads "0.50", "2.10" mm; {10} m "10.0" m; {0.004} m "4.0" mm. The same values
// give the same texts wherever they are printed (console and page).
inline constexpr int kMaxRowDecimals = 4;
ValuesInOneUnit FormatRowInOneUnit(const std::vector<double>& values, const std::string& kind);

// Columns of a table whose rows are of different kinds (e.g. the groups of an adjustment: marks in
// px, points in m, attitudes in deg), the columns of one row read together (stated, RMS,
// estimated): every value of one kind, over all the columns, in one unit (FormatInOneUnit), so
// that a column never mixes mm and cm. When every row has the same unit, `unit` names it for the
// headers; otherwise `unit` is empty and the table takes a unit column (`units`, one per row).
// Cells never carry a unit.
struct ColumnsInUnits {
  std::vector<std::vector<std::string>> texts;  // [column][row], without the unit
  std::vector<std::string> units;               // [row]: its kind's unit
  std::string unit;                             // the unit of every row, or empty
};
ColumnsInUnits FormatColumnsInUnits(const std::vector<std::vector<double>>& columns,
                                    const std::vector<std::string>& row_kinds);

// Angles: degrees with four decimals, arc seconds (of a value in degrees) with one.
std::string FormatDegrees(double value_deg);
std::string FormatArcSeconds(double value_deg);
// A unitless figure (sigma0, ratios, w, correlations) with `decimals` decimals.
std::string FormatUnitless(double value, int decimals = 2);
// `value` with `significant` significant digits in fixed notation (at most 6 decimals, so below
// 0.0000005 it prints "0"): times, counts per second, calibration values.
std::string FormatSignificant(double value, int significant = 3);
// A value someone chose (a sweep's setting, an initial error, a threshold: an input, not a
// measured error) with its unit and at most 4 significant digits (FormatSignificant), lengths and
// angles in the unit that puts the magnitude in [0.1, 1000): lengths (m) in mm, m or km ("50 mm",
// "0.5 m", "2.5 km"), angles (deg) in arc seconds or degrees ("36 arcsec", "2 deg"); the smallest
// unit below that range, the largest above it; 0 in the base unit ("0 m"); "n/a" when not finite.
std::string FormatScaledLength(double value_m);
std::string FormatScaledAngle(double value_deg);
// A calibration value and its sigma (units of core/camera_models.h) at the sigma's precision: the
// sigma to two significant digits, the value to the same decimals ("24012.3" +- "1.2"; at most
// kMaxCoefficientDecimals); without a positive sigma, the value to 6 significant digits
// (FormatSignificant). Small coefficients (magnitude of the larger below 1e-3, e.g. K1 ~ 1e-4
// mm^-2, K2 ~ 1e-7 mm^-4) in the power of ten of the larger, named in `scale` ("10^-4"; empty
// when not scaled), so that both keep their digits without an exponent. The unit of a camera
// parameter: CameraParamUnit.
inline constexpr int kMaxCoefficientDecimals = 8;
struct CoefficientTexts {
  std::string value;
  std::string sigma;  // "n/a" when not finite
  std::string scale;  // "10^-4" or empty
};
CoefficientTexts FormatCoefficient(double value, double sigma);
// The unit of camera parameter `name` of a `model` camera (core/camera_models.h): "um", "mm^-2",
// "mm^-4", "mm^-6", "mm^-1" for the frame model, "px" for the focal lengths and principal points
// of the pixel models, "unitless" for the rest.
std::string CameraParamUnit(CameraModelType model, const std::string& name);

// A unit as it reads in UTF-8 text (the HTML pages, whose head declares UTF-8): "um" -> "µm",
// "us" -> "µs"; any other unchanged. The ASCII names stay where a program reads them (JSON, CSV
// headers, file formats) and on the console, whose encoding is not known.
std::string Utf8UnitName(const std::string& unit);
// Where a text that names a unit is read: kAscii on the console and in files, kUtf8 on a page;
// UnitNameFor gives the unit's name there (Utf8UnitName on a page, unchanged otherwise). For a
// sentence shared by the console and a page (a warning in words).
enum class UnitText { kAscii, kUtf8 };
std::string UnitNameFor(const std::string& unit, UnitText text);

// "1 image", "12 images".
std::string FormatCount(long long count, const std::string& singular,
                        const std::string& plural = "");

}  // namespace photopose
