#include "core/units.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

namespace photopose {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

std::string ReportFixed(double value, int digits) {
  if (!std::isfinite(value)) return "n/a";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*f", digits, value);
  return buffer;
}

LengthUnit LengthUnitFor(double largest_magnitude_m) {
  const double m = std::abs(largest_magnitude_m);
  if (!(m >= 0.1)) return LengthUnit::kMillimetre;  // NaN too
  if (m < 10.0) return LengthUnit::kCentimetre;
  return LengthUnit::kMetre;
}

double LargestMagnitude(const std::vector<double>& values) {
  double largest = 0.0;
  for (const double v : values)
    if (std::isfinite(v)) largest = std::max(largest, std::abs(v));
  return largest;
}

const char* LengthUnitName(LengthUnit unit) { return EnumName(unit); }

double LengthIn(double value_m, LengthUnit unit) {
  switch (unit) {
    case LengthUnit::kMillimetre:
      return 1000.0 * value_m;
    case LengthUnit::kCentimetre:
      return 100.0 * value_m;
    default:
      return value_m;
  }
}

std::string FormatLength(double value_m, LengthUnit unit) {
  return ReportFixed(LengthIn(value_m, unit), unit == LengthUnit::kMetre ? 3 : 1);
}

std::string FormatLengthWithUnit(double value_m) { return FormatLengthsWithUnit({value_m})[0]; }

std::vector<std::string> FormatLengthsWithUnit(const std::vector<double>& values_m) {
  return FormatMarkValues(values_m, "m");
}

std::string FormatCoordinate(double value_m) { return ReportFixed(value_m, 3); }
std::string FormatPixels(double value_px) { return ReportFixed(value_px, 2); }
std::string FormatFilm(double value_um) { return ReportFixed(value_um, 2); }

ValuesInOneUnit FormatInOneUnit(const std::vector<double>& values, const std::string& kind) {
  ValuesInOneUnit out;
  if (kind == "m") {
    const LengthUnit unit = LengthUnitFor(LargestMagnitude(values));
    out.unit = LengthUnitName(unit);
    for (const double v : values) out.texts.push_back(FormatLength(v, unit));
  } else if (kind == "deg") {
    out.unit = "arcsec";
    for (const double v : values) out.texts.push_back(FormatArcSeconds(v));
  } else {
    out.unit = kind;
    for (const double v : values) out.texts.push_back(ReportFixed(v, 2));
  }
  return out;
}

std::vector<std::string> FormatMarkValues(const std::vector<double>& values,
                                          const std::string& kind) {
  ValuesInOneUnit in_one = FormatInOneUnit(values, kind);
  for (size_t k = 0; k < values.size(); ++k)
    if (std::isfinite(values[k])) in_one.texts[k] += " " + in_one.unit;
  return in_one.texts;
}

std::string FormatMarkValue(double value, const std::string& kind) {
  return FormatMarkValues({value}, kind)[0];
}

namespace {

// Decimals that give `magnitude` (> 0, in the unit it is printed in) two significant digits.
int DecimalsForTwoDigits(double magnitude) {
  return 1 - static_cast<int>(std::floor(std::log10(magnitude)));
}

// The smallest finite non-zero magnitude of `values`, or 0 when there is none.
double SmallestNonZeroMagnitude(const std::vector<double>& values) {
  double smallest = 0.0;
  for (const double v : values)
    if (std::isfinite(v) && v != 0.0 && (smallest == 0.0 || std::abs(v) < smallest))
      smallest = std::abs(v);
  return smallest;
}

}  // namespace

ValuesInOneUnit FormatRowInOneUnit(const std::vector<double>& values, const std::string& kind) {
  ValuesInOneUnit out;
  const double smallest = SmallestNonZeroMagnitude(values);
  // The unit and the values in it (`scale` times the kind's unit).
  double scale = 1.0;
  int least_decimals = 2;  // marks in px, um or sigma
  if (kind == "m") {
    LengthUnit unit = LengthUnitFor(LargestMagnitude(values));
    while (unit != LengthUnit::kMillimetre && smallest > 0.0 &&
           DecimalsForTwoDigits(LengthIn(smallest, unit)) > kMaxRowDecimals)
      unit = unit == LengthUnit::kMetre ? LengthUnit::kCentimetre : LengthUnit::kMillimetre;
    out.unit = LengthUnitName(unit);
    scale = LengthIn(1.0, unit);
    least_decimals = 1;
  } else if (kind == "deg") {
    out.unit = "arcsec";
    scale = 3600.0;
    least_decimals = 1;
  } else {
    out.unit = kind;
  }
  const int decimals = smallest > 0.0 ? std::clamp(DecimalsForTwoDigits(scale * smallest),
                                                   least_decimals, kMaxRowDecimals)
                                      : least_decimals;
  for (const double v : values) out.texts.push_back(ReportFixed(scale * v, decimals));
  return out;
}

ColumnsInUnits FormatColumnsInUnits(const std::vector<std::vector<double>>& columns,
                                    const std::vector<std::string>& row_kinds) {
  ColumnsInUnits out;
  const size_t num_rows = row_kinds.size();
  out.texts.assign(columns.size(), std::vector<std::string>(num_rows));
  out.units.assign(num_rows, "");
  // Each kind's values over every column and row, in one unit.
  std::vector<std::string> kinds(row_kinds);
  std::sort(kinds.begin(), kinds.end());
  kinds.erase(std::unique(kinds.begin(), kinds.end()), kinds.end());
  for (const std::string& kind : kinds) {
    std::vector<double> values;
    for (const std::vector<double>& column : columns)
      for (size_t r = 0; r < num_rows; ++r)
        if (row_kinds[r] == kind) values.push_back(r < column.size() ? column[r] : kNaN);
    const ValuesInOneUnit in_one = FormatInOneUnit(values, kind);
    size_t k = 0;
    for (size_t c = 0; c < columns.size(); ++c)
      for (size_t r = 0; r < num_rows; ++r)
        if (row_kinds[r] == kind) out.texts[c][r] = in_one.texts[k++];
    for (size_t r = 0; r < num_rows; ++r)
      if (row_kinds[r] == kind) out.units[r] = in_one.unit;
  }
  if (!out.units.empty() &&
      std::all_of(out.units.begin(), out.units.end(),
                  [&](const std::string& u) { return u == out.units.front(); }))
    out.unit = out.units.front();
  return out;
}

std::string FormatDegrees(double value_deg) { return ReportFixed(value_deg, 4); }
std::string FormatArcSeconds(double value_deg) { return ReportFixed(3600.0 * value_deg, 1); }
std::string FormatUnitless(double value, int decimals) { return ReportFixed(value, decimals); }

std::string FormatSignificant(double value, int significant) {
  if (!std::isfinite(value)) return "n/a";
  if (value == 0.0) return "0";
  const int magnitude = static_cast<int>(std::floor(std::log10(std::abs(value))));
  const int decimals = std::clamp(significant - 1 - magnitude, 0, 6);
  std::string text = ReportFixed(value, decimals);
  // Trailing zeros of the decimals say nothing.
  if (text.find('.') != std::string::npos) {
    while (text.back() == '0') text.pop_back();
    if (text.back() == '.') text.pop_back();
  }
  return text == "-0" ? "0" : text;
}

namespace {

// A unit of a quantity and its size in the quantity's base unit (m, deg).
struct ScaledUnit {
  const char* name;
  double size;
};

// `value` (base unit) in the largest of `ladder` (ascending sizes) in which its magnitude is at
// least 0.1, the smallest when none is; 0 in the base unit.
std::string FormatScaled(double value, const std::vector<ScaledUnit>& ladder, const char* base) {
  if (!std::isfinite(value)) return "n/a";
  if (value == 0.0) return std::string("0 ") + base;
  const ScaledUnit* unit = &ladder.front();
  for (const ScaledUnit& u : ladder)
    if (std::abs(value) / u.size >= 0.1) unit = &u;
  return FormatSignificant(value / unit->size, 4) + " " + unit->name;
}

}  // namespace

std::string FormatScaledLength(double value_m) {
  return FormatScaled(value_m, {{"mm", 1e-3}, {"m", 1.0}, {"km", 1e3}}, "m");
}

std::string FormatScaledAngle(double value_deg) {
  return FormatScaled(value_deg, {{"arcsec", 1.0 / 3600.0}, {"deg", 1.0}}, "deg");
}

CoefficientTexts FormatCoefficient(double value, double sigma) {
  const double magnitude =
      std::max(std::isfinite(value) ? std::abs(value) : 0.0, std::isfinite(sigma) ? sigma : 0.0);
  const int exponent =
      magnitude > 0.0 && magnitude < 1e-3 ? static_cast<int>(std::floor(std::log10(magnitude))) : 0;
  const double scale = std::pow(10.0, -exponent);
  const std::string power = exponent != 0 ? "10^" + std::to_string(exponent) : "";
  if (!(std::isfinite(sigma) && sigma > 0.0) || !std::isfinite(value))
    return {FormatSignificant(value * scale, 6), FormatSignificant(sigma * scale, 3), power};
  // The sigma to two significant digits, the value to the same decimals: no digit the sigma
  // says is noise beyond the one after its first.
  const int decimals = std::clamp(DecimalsForTwoDigits(sigma * scale), 0, kMaxCoefficientDecimals);
  std::string text = ReportFixed(value * scale, decimals);
  if (std::strtod(text.c_str(), nullptr) == 0.0) text = ReportFixed(0.0, decimals);  // no "-0.00"
  return {text, ReportFixed(sigma * scale, decimals), power};
}

std::string CameraParamUnit(CameraModelType model, const std::string& name) {
  if (model == CameraModelType::kFrame) {
    if (name == "FocalLength" || name == "PrincipalX" || name == "PrincipalY") return "um";
    if (name == "K1") return "mm^-2";
    if (name == "K2") return "mm^-4";
    if (name == "K3") return "mm^-6";
    if (name == "P1" || name == "P2") return "mm^-1";
    return "unitless";
  }
  if (name == "f" || name == "fx" || name == "fy" || name == "cx" || name == "cy") return "px";
  return "unitless";
}

std::string Utf8UnitName(const std::string& unit) {
  if (unit == "um") return "\u00b5m";
  if (unit == "us") return "\u00b5s";
  return unit;
}

std::string UnitNameFor(const std::string& unit, UnitText text) {
  return text == UnitText::kUtf8 ? Utf8UnitName(unit) : unit;
}

std::string FormatCount(long long count, const std::string& singular, const std::string& plural) {
  return std::to_string(count) + " " +
         (count == 1 ? singular : (plural.empty() ? singular + "s" : plural));
}

}  // namespace photopose
