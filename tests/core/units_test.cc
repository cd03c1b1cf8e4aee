#include "core/units.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

TEST(Units, FixedDecimalsSayNaWhenNotFinite) {
  EXPECT_EQ(ReportFixed(1.23456, 2), "1.23");
  EXPECT_EQ(ReportFixed(-0.5, 0), "-0");
  EXPECT_EQ(ReportFixed(INFINITY, 3), "n/a");
  EXPECT_EQ(ReportFixed(std::nan(""), 1), "n/a");
}

TEST(Units, LengthsTakeTheUnitTheirMagnitudeCallsFor) {
  EXPECT_EQ(LengthUnitFor(0.0123), LengthUnit::kMillimetre);
  EXPECT_EQ(LengthUnitFor(0.25), LengthUnit::kCentimetre);
  EXPECT_EQ(LengthUnitFor(12.0), LengthUnit::kMetre);
  EXPECT_EQ(LengthUnitFor(std::nan("")), LengthUnit::kMillimetre);
  EXPECT_EQ(FormatLength(-6.97e-05, LengthUnit::kMillimetre), "-0.1");
  EXPECT_EQ(FormatLength(0.0267, LengthUnit::kCentimetre), "2.7");
  EXPECT_EQ(FormatLength(1.2345, LengthUnit::kMetre), "1.234");  // 1.2345 is below it in binary
  EXPECT_EQ(FormatLengthWithUnit(0.0069), "6.9 mm");
  EXPECT_EQ(FormatLengthWithUnit(1.24), "124.0 cm");
  EXPECT_EQ(FormatLengthWithUnit(std::nan("")), "n/a");
  EXPECT_DOUBLE_EQ(LengthIn(0.5, LengthUnit::kCentimetre), 50.0);
}

// Figures printed side by side take one unit, the one their largest magnitude calls for.
TEST(Units, LengthsOfOneLineShareOneUnit) {
  EXPECT_EQ(FormatLengthsWithUnit({10.0, 2.787}), (std::vector<std::string>{"10.000 m", "2.787 m"}));
  EXPECT_EQ(FormatLengthsWithUnit({0.005, 0.25}), (std::vector<std::string>{"0.5 cm", "25.0 cm"}));
  EXPECT_EQ(FormatLengthsWithUnit({0.005, std::nan(""), -0.0069}),
            (std::vector<std::string>{"5.0 mm", "n/a", "-6.9 mm"}));
  EXPECT_EQ(FormatLengthsWithUnit({}), std::vector<std::string>{});
  // A group's values: lengths share a unit, pixels, micrometres and arc seconds are fixed.
  EXPECT_EQ(FormatMarkValues({10.0, 2.787}, "m"), (std::vector<std::string>{"10.000 m", "2.787 m"}));
  EXPECT_EQ(FormatMarkValues({0.5, 18.6}, "px"), (std::vector<std::string>{"0.50 px", "18.60 px"}));
  EXPECT_EQ(FormatMarkValues({0.01, 0.0000214}, "deg"),
            (std::vector<std::string>{"36.0 arcsec", "0.1 arcsec"}));
}

// A table column of several groups: every length of the table in one unit, chosen once from the
// largest (not 5.0 mm in one row and 50.0 cm in the next); other kinds in their fixed units; the
// unit named once (for the header) when every row shares it.
TEST(Units, ColumnsOfSeveralKindsTakeOneUnitPerKind) {
  const ValuesInOneUnit lengths = FormatInOneUnit({0.005, 0.5, std::nan("")}, "m");
  EXPECT_EQ(lengths.unit, "cm");
  EXPECT_EQ(lengths.texts, (std::vector<std::string>{"0.5", "50.0", "n/a"}));
  EXPECT_EQ(FormatInOneUnit({0.01}, "deg").unit, "arcsec");
  EXPECT_EQ(FormatInOneUnit({0.01}, "deg").texts[0], "36.0");
  EXPECT_EQ(FormatInOneUnit({0.456}, "um").texts[0], "0.46");

  // Rows: control points (m), camera positions (m), tie marks (px); columns stated and RMS.
  const ColumnsInUnits mixed =
      FormatColumnsInUnits({{0.005, 0.5, 0.5}, {0.003, 0.2, 0.43}}, {"m", "m", "px"});
  EXPECT_EQ(mixed.unit, "");  // lengths and pixels: a unit column
  EXPECT_EQ(mixed.units, (std::vector<std::string>{"cm", "cm", "px"}));
  EXPECT_EQ(mixed.texts[0], (std::vector<std::string>{"0.5", "50.0", "0.50"}));
  EXPECT_EQ(mixed.texts[1], (std::vector<std::string>{"0.3", "20.0", "0.43"}));
  // The largest of any column sets the unit of the kind in all of them.
  const ColumnsInUnits lengths_only =
      FormatColumnsInUnits({{0.005, 0.002}, {0.003, 0.2}}, {"m", "m"});
  EXPECT_EQ(lengths_only.unit, "cm");
  EXPECT_EQ(lengths_only.texts[0], (std::vector<std::string>{"0.5", "0.2"}));
  for (const auto& column : {mixed.texts[0], mixed.texts[1], lengths_only.texts[1]})
    for (const std::string& cell : column)
      EXPECT_EQ(cell.find_first_of("abcdefghijklmnopqrstuvwxyz"), std::string::npos) << cell;
  EXPECT_EQ(FormatColumnsInUnits({{}}, {}).unit, "");
}

// The figures of one row (a group's stated, RMS, estimated accuracy): the unit from the row's own
// magnitudes, every value with at least two significant digits, at most four decimals, never an
// exponent.
TEST(Units, ARowTakesItsOwnUnitAndTwoSignificantDigits) {
  // An RMS of 0.5 mm beside 2.1 mm: not "0.1 cm" and "0.2 cm".
  ValuesInOneUnit row = FormatRowInOneUnit({0.0005, 0.0021}, "m");
  EXPECT_EQ(row.unit, "mm");
  EXPECT_EQ(row.texts, (std::vector<std::string>{"0.50", "2.10"}));
  row = FormatRowInOneUnit({0.004, 0.002}, "m");  // not "0.004 / 0.002 m"
  EXPECT_EQ(row.unit, "mm");
  EXPECT_EQ(row.texts, (std::vector<std::string>{"4.0", "2.0"}));
  row = FormatRowInOneUnit({10.0, std::nan("")}, "m");  // a stated 10 m, nothing estimated
  EXPECT_EQ(row.unit, "m");
  EXPECT_EQ(row.texts, (std::vector<std::string>{"10.0", "n/a"}));
  row = FormatRowInOneUnit({0.5, 0.04}, "m");
  EXPECT_EQ(row.unit, "cm");
  EXPECT_EQ(row.texts, (std::vector<std::string>{"50.0", "4.0"}));
  // 10 m beside 0.04 mm: in m the smallest would need six decimals, in cm it needs four.
  row = FormatRowInOneUnit({10.0, 0.00004}, "m");
  EXPECT_EQ(row.unit, "cm");
  EXPECT_EQ(row.texts, (std::vector<std::string>{"1000.0000", "0.0040"}));
  // Zero has no significant digit to keep; below 4 decimals in mm the value rounds.
  EXPECT_EQ(FormatRowInOneUnit({0.0, 0.003}, "m").texts, (std::vector<std::string>{"0.0", "3.0"}));
  EXPECT_EQ(FormatRowInOneUnit({1e-9}, "m").texts[0], "0.0000");
  // Marks keep two decimals, more for a small figure; attitudes in arc seconds.
  EXPECT_EQ(FormatRowInOneUnit({0.5, 0.43}, "px").texts,
            (std::vector<std::string>{"0.50", "0.43"}));
  EXPECT_EQ(FormatRowInOneUnit({0.5, 0.004}, "px").texts,
            (std::vector<std::string>{"0.5000", "0.0040"}));
  row = FormatRowInOneUnit({0.01, 0.005}, "deg");
  EXPECT_EQ(row.unit, "arcsec");
  EXPECT_EQ(row.texts, (std::vector<std::string>{"36.0", "18.0"}));
  EXPECT_EQ(FormatRowInOneUnit({0.01, 0.0000214}, "deg").texts,
            (std::vector<std::string>{"36.000", "0.077"}));
  for (const double v : {1e-12, 3e-7, 0.0123, 7.0, 12345.6})
    for (const std::string& text : FormatRowInOneUnit({v, 2 * v}, "m").texts)
      EXPECT_EQ(text.find_first_of("eE"), std::string::npos) << text;
}

TEST(Units, MicroUnitsReadAsMicroInUtf8) {
  EXPECT_EQ(Utf8UnitName("um"), "\u00b5m");
  EXPECT_EQ(Utf8UnitName("us"), "\u00b5s");
  EXPECT_EQ(Utf8UnitName("mm"), "mm");
  EXPECT_EQ(Utf8UnitName(""), "");
  // A sentence shared by the console (ASCII) and a page (UTF-8).
  EXPECT_EQ(UnitNameFor("um", UnitText::kAscii), "um");
  EXPECT_EQ(UnitNameFor("um", UnitText::kUtf8), "\u00b5m");
  EXPECT_EQ(UnitNameFor("px", UnitText::kUtf8), "px");
}

// Values someone chose: at most 4 significant digits, scaled into 0.1 to 1000 of a unit.
TEST(Units, ChosenValuesTakeTheUnitThatKeepsThemReadable) {
  EXPECT_EQ(FormatScaledLength(5.0), "5 m");
  EXPECT_EQ(FormatScaledLength(0.5), "0.5 m");
  EXPECT_EQ(FormatScaledLength(0.05), "50 mm");
  EXPECT_EQ(FormatScaledLength(0.0001), "0.1 mm");
  EXPECT_EQ(FormatScaledLength(1e-5), "0.01 mm");  // below the range: the smallest unit
  EXPECT_EQ(FormatScaledLength(2500.0), "2.5 km");
  EXPECT_EQ(FormatScaledLength(1.23456), "1.235 m");
  EXPECT_EQ(FormatScaledLength(0.0), "0 m");
  EXPECT_EQ(FormatScaledLength(std::nan("")), "n/a");
  EXPECT_EQ(FormatScaledAngle(2.0), "2 deg");
  EXPECT_EQ(FormatScaledAngle(0.05), "180 arcsec");
  EXPECT_EQ(FormatScaledAngle(1e-5), "0.036 arcsec");
  EXPECT_EQ(FormatScaledAngle(-0.25), "-0.25 deg");
}

TEST(Units, NumbersNeverTakeAnExponent) {
  EXPECT_EQ(FormatSignificant(0.000697, 3), "0.000697");
  EXPECT_EQ(FormatSignificant(6.97e-05, 3), "0.00007");  // at most six decimals
  EXPECT_EQ(FormatSignificant(2.45e-09, 3), "0");
  EXPECT_EQ(FormatSignificant(1234567.0, 3), "1234567");
  EXPECT_EQ(FormatSignificant(0.5, 3), "0.5");
  EXPECT_EQ(FormatSignificant(-12.345, 3), "-12.3");
  EXPECT_EQ(FormatArcSeconds(1.0 / 3600.0), "1.0");
  EXPECT_EQ(FormatDegrees(12.3456789), "12.3457");
  EXPECT_EQ(FormatPixels(0.456), "0.46");
  EXPECT_EQ(FormatMarkValue(0.5, "px"), "0.50 px");
  EXPECT_EQ(FormatMarkValue(0.005, "m"), "5.0 mm");  // a control point group's accuracy
  EXPECT_EQ(FormatMarkValue(6.97e-05, "m"), "0.1 mm");
  EXPECT_EQ(FormatMarkValue(0.01, "deg"), "36.0 arcsec");  // an attitude group's
  EXPECT_EQ(FormatUnitless(0.0839), "0.08");
  EXPECT_EQ(FormatCount(1, "image"), "1 image");
  EXPECT_EQ(FormatCount(12, "image"), "12 images");
  EXPECT_EQ(FormatCount(2, "check mark"), "2 check marks");
}

// Calibration values: small coefficients in a power of ten named beside the unit, the value at its
// sigma's precision (the sigma to two significant digits, the value to the same decimals); the
// unit of each parameter from the camera model.
TEST(Units, SmallCoefficientsTakeANamedPowerOfTen) {
  const CoefficientTexts k1 = FormatCoefficient(-1.234567e-4, 2.5e-7);
  EXPECT_EQ(k1.scale, "10^-4");
  EXPECT_EQ(k1.value, "-1.2346");
  EXPECT_EQ(k1.sigma, "0.0025");
  const CoefficientTexts focal = FormatCoefficient(24012.3456, 1.23);
  EXPECT_EQ(focal.scale, "");
  EXPECT_EQ(focal.value, "24012.3");
  EXPECT_EQ(focal.sigma, "1.2");
  const CoefficientTexts principal = FormatCoefficient(-12.345678, 0.0456);
  EXPECT_EQ(principal.value, "-12.346");
  EXPECT_EQ(principal.sigma, "0.046");
  const CoefficientTexts loose = FormatCoefficient(24012.3456, 123.4);
  EXPECT_EQ(loose.value, "24012");
  EXPECT_EQ(loose.sigma, "123");
  EXPECT_EQ(FormatCoefficient(-0.00001, 0.01).value, "0.000");  // no "-0.000"
  // Without a sigma: the value to 6 significant digits.
  EXPECT_EQ(FormatCoefficient(24012.3456, std::nan("")).value, "24012.3");
  EXPECT_EQ(FormatCoefficient(3e-9, std::nan("")).scale, "10^-9");
  EXPECT_EQ(FormatCoefficient(3e-9, std::nan("")).sigma, "n/a");
  EXPECT_EQ(FormatCoefficient(0.0, 0.0).scale, "");
  EXPECT_EQ(CameraParamUnit(CameraModelType::kFrame, "FocalLength"), "um");
  EXPECT_EQ(CameraParamUnit(CameraModelType::kFrame, "K2"), "mm^-4");
  EXPECT_EQ(CameraParamUnit(CameraModelType::kFrame, "P1"), "mm^-1");
  EXPECT_EQ(CameraParamUnit(CameraModelType::kPinhole, "fx"), "px");
  EXPECT_EQ(CameraParamUnit(CameraModelType::kSimpleRadial, "k"), "unitless");
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
