#include "core/enum_names.h"

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "core/block.h"
#include "core/camera.h"
#include "core/pixel_rows.h"
#include "core/camera_models.h"
#include "core/io/exif_gps.h"
#include "core/units.h"
#include "core/rotation.h"
#include "core/simulation/synthetic_scene.h"
#include "core/termination.h"
#include "cost_functions/collinearity_cost.h"
#include "cost_functions/losses.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/resection/pose_refinement.h"
#include "solvers/resection/resection.h"
#include "solvers/resection/taylor_resection.h"
#include "tools/compare/comparison.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// ------------------------------------------------------------------ the mechanism, on a table of
// its own

enum class Fruit { kApple, kPear, kQuince };
inline constexpr EnumNameEntry<Fruit> kFruitNames[] = {{Fruit::kApple, "apple"},
                                                       {Fruit::kPear, "pear"},
                                                       {Fruit::kQuince, "quince"},
                                                       {Fruit::kPear, "poire"},
                                                       {Fruit::kPear, "birne"}};
constexpr EnumNameTable<Fruit> EnumNames(Fruit) { return EnumNameTable<Fruit>(kFruitNames); }

enum class Shade { kLight, kDark };
inline constexpr EnumNameEntry<Shade> kShadeNames[] = {{Shade::kLight, "LIGHT"},
                                                       {Shade::kDark, "DARK"}};
constexpr EnumNameTable<Shade> EnumNames(Shade) {
  return EnumNameTable<Shade>(kShadeNames, NameMatch::kIgnoreCase);
}

TEST(EnumNames, PrintsTheFirstNameOfAValue) {
  EXPECT_STREQ(EnumName(Fruit::kApple), "apple");
  EXPECT_STREQ(EnumName(Fruit::kPear), "pear");  // not an alias
  EXPECT_STREQ(EnumName(static_cast<Fruit>(7)), "?");
}

TEST(EnumNames, ParsesNamesAndAliasesExactly) {
  Fruit fruit = Fruit::kApple;
  EXPECT_TRUE(ParseEnum("quince", &fruit));
  EXPECT_EQ(fruit, Fruit::kQuince);
  EXPECT_TRUE(ParseEnum("birne", &fruit));
  EXPECT_EQ(fruit, Fruit::kPear);
  // Unknown text, another case, a prefix, an empty string: refused, the value left as it was.
  for (const char* text : {"Pear", "pea", "pears", "", "banana"}) {
    fruit = Fruit::kQuince;
    EXPECT_FALSE(ParseEnum(text, &fruit)) << text;
    EXPECT_EQ(fruit, Fruit::kQuince) << text;
  }
  EXPECT_EQ(ParseEnum<Fruit>("poire"), Fruit::kPear);
  EXPECT_FALSE(ParseEnum<Fruit>("POIRE").has_value());
}

TEST(EnumNames, IgnoresCaseWhereTheTableSaysSo) {
  EXPECT_EQ(ParseEnum<Shade>("dark"), Shade::kDark);
  EXPECT_EQ(ParseEnum<Shade>("LiGhT"), Shade::kLight);
  EXPECT_FALSE(ParseEnum<Shade>("darker").has_value());
  EXPECT_FALSE(ParseEnum<Shade>("d\xC3\xA4rk").has_value());  // only ASCII letters fold
}

TEST(EnumNames, ListsTheChoicesWithTheirAliases) {
  EXPECT_EQ(EnumChoices<Fruit>(), "apple, pear (aliases poire, birne) or quince");
  EXPECT_EQ(EnumChoices<Shade>(), "LIGHT or DARK");
  const Fruit some[] = {Fruit::kQuince, Fruit::kApple};
  EXPECT_EQ(EnumNameList(some), "quince or apple");
  const Fruit one[] = {Fruit::kPear};
  EXPECT_EQ(EnumNameList(one), "pear");
}

// ------------------------------------------------------------------ every table of photopose

// Every value first..first+n-1 of the enum (n its number of names; first 0 unless the enum's
// values are numbered otherwise) has a name that parses back to it (in
// any case when the table ignores case); every alias parses to its value; names and aliases are
// unique (after case folding where the table folds); and an unknown name is refused while
// EnumChoices lists every name.
template <typename Enum>
void ExpectTableRoundTrips(const char* what, int first = 0) {
  SCOPED_TRACE(what);
  const EnumNameTable<Enum> table = EnumNames(Enum{});
  const bool fold = table.match() == NameMatch::kIgnoreCase;
  auto folded = [fold](std::string text) {
    if (fold)
      for (char& c : text)
        if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    return text;
  };
  std::set<int> values;
  std::set<std::string> spellings;
  for (const EnumNameEntry<Enum>& entry : table) {
    values.insert(static_cast<int>(entry.value));
    EXPECT_TRUE(spellings.insert(folded(entry.name)).second) << "twice: " << entry.name;
    Enum parsed{};
    ASSERT_TRUE(ParseEnum(entry.name, &parsed)) << entry.name;
    EXPECT_EQ(parsed, entry.value) << entry.name;
  }
  const int n = static_cast<int>(values.size());
  ASSERT_GT(n, 0);
  EXPECT_EQ(*values.begin(), first);
  EXPECT_EQ(*values.rbegin(), first + n - 1) << "the values are not first..first+n-1";
  const std::string choices = EnumChoices<Enum>();
  for (int k = first; k < first + n; ++k) {
    const Enum value = static_cast<Enum>(k);
    const std::string name = EnumName(value);
    ASSERT_NE(name, "?") << "value " << k << " has no name";
    EXPECT_EQ(ParseEnum<Enum>(name), value) << name;
    if (fold) {
      std::string upper = name;
      for (char& c : upper)
        if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
      std::string lower = folded(name);
      EXPECT_EQ(ParseEnum<Enum>(upper), value) << upper;
      EXPECT_EQ(ParseEnum<Enum>(lower), value) << lower;
    }
    EXPECT_NE(choices.find(name), std::string::npos) << choices << " lacks " << name;
  }
  EXPECT_FALSE(ParseEnum<Enum>("no_such_name").has_value()) << choices;
  EXPECT_FALSE(ParseEnum<Enum>("").has_value()) << choices;
}

TEST(EnumNames, EveryTableRoundTrips) {
  ExpectTableRoundTrips<RotationConvention>("RotationConvention");
  ExpectTableRoundTrips<CameraModelType>("CameraModelType");
  ExpectTableRoundTrips<MarkUnit>("MarkUnit");
  ExpectTableRoundTrips<PixelOrigin>("PixelOrigin");
  ExpectTableRoundTrips<PixelRows>("PixelRows");
  ExpectTableRoundTrips<Scenario>("Scenario");
  ExpectTableRoundTrips<SolverTermination>("SolverTermination");
  ExpectTableRoundTrips<LossType>("LossType");
  ExpectTableRoundTrips<JacobianType>("JacobianType");
  ExpectTableRoundTrips<PoseSolver>("PoseSolver");
  ExpectTableRoundTrips<CeresMinimizer>("CeresMinimizer");
  ExpectTableRoundTrips<TaylorPartials>("TaylorPartials");
  ExpectTableRoundTrips<MarkStatus>("MarkStatus");
  ExpectTableRoundTrips<BundleLinearSolver>("BundleLinearSolver");
  ExpectTableRoundTrips<BundleDatum>("BundleDatum");
  ExpectTableRoundTrips<BundleGroup>("BundleGroup");
  ExpectTableRoundTrips<cli::SweepType>("SweepType");
  ExpectTableRoundTrips<cli::InitialValues>("InitialValues");
  ExpectTableRoundTrips<PointRole>("PointRole");
  ExpectTableRoundTrips<FilmCoordinateSystem>("FilmCoordinateSystem", /*first=*/1);
  ExpectTableRoundTrips<DistortionType>("DistortionType");
  ExpectTableRoundTrips<OrientationType>("OrientationType");
  ExpectTableRoundTrips<ExifGpsSource>("ExifGpsSource");
  ExpectTableRoundTrips<LengthUnit>("LengthUnit");
}

// The spellings every output and report prints (JSON keys and values, CSV, console), and the
// accepted aliases, by table: a change here changes a file format (docs/formats.md).
TEST(EnumNames, PrintedNamesAndAliasesAreThoseOfTheFormats) {
  EXPECT_EQ(EnumChoices<RotationConvention>(), "rxryrz (alias seed), opk or pok");
  EXPECT_EQ(ParseEnum<RotationConvention>("Seed"), RotationConvention::kSeed);
  EXPECT_EQ(EnumChoices<SolverTermination>(), "converged, no_convergence, failure or cancelled");
  EXPECT_EQ(EnumChoices<LossType>(), "none, huber, softl1, cauchy, arctan or tukey");
  EXPECT_EQ(EnumNameList(kBundleTieLosses), "none, huber, cauchy or softl1");
  EXPECT_EQ(EnumChoices<JacobianType>(), "analytic or autodiff");
  EXPECT_EQ(EnumChoices<PoseSolver>(), "ceres, taylor or taylor_as_printed");
  EXPECT_EQ(EnumChoices<CeresMinimizer>(), "tiny_solver or problem");
  EXPECT_EQ(EnumChoices<TaylorPartials>(), "corrected or as_printed (aliases as-printed, printed)");
  EXPECT_EQ(EnumChoices<BundleLinearSolver>(),
            "sparse_schur, dense_schur, iterative_schur_jacobi (alias iterative_schur) or "
            "iterative_schur_cluster_jacobi");
  EXPECT_EQ(EnumChoices<BundleGroup>(),
            "tie_marks, control_marks, control_points, camera_positions or attitudes");
  EXPECT_EQ(EnumChoices<BundleDatum>(), "absolute or relative");
  EXPECT_EQ(EnumChoices<CameraModelType>(),
            "FRAME, SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, FULL_OPENCV or "
            "OPENCV_FISHEYE");
  EXPECT_EQ(EnumChoices<MarkStatus>(), "accepted, outlier or rejected");
  EXPECT_EQ(EnumChoices<MarkUnit>(), "px or um");
  EXPECT_EQ(EnumChoices<PixelOrigin>(), "corner or center");
  EXPECT_EQ(EnumChoices<PixelRows>(), "down or up");
  EXPECT_EQ(EnumChoices<Scenario>(), "nadir, oblique or uav_block");
  EXPECT_EQ(EnumChoices<cli::SweepType>(), "axes or grid");
  EXPECT_EQ(EnumChoices<cli::InitialValues>(), "frames or ransac");
  EXPECT_EQ(EnumChoices<PointRole>(), "control, check or tie");
  EXPECT_EQ(EnumChoices<FilmCoordinateSystem>(),
            "1 (alias X_RIGHT_Y_UP), 2 (alias X_UP_Y_LEFT), 3 (alias X_LEFT_Y_DOWN) or 4 (alias "
            "X_DOWN_Y_RIGHT)");
  EXPECT_EQ(EnumChoices<DistortionType>(), "DistortionModel or DistortionTable");
  EXPECT_EQ(EnumChoices<OrientationType>(), "OPK or Matrix");
  EXPECT_EQ(EnumChoices<ExifGpsSource>(), "exif or dji_xmp");
  EXPECT_EQ(EnumChoices<LengthUnit>(), "mm, cm or m");
  EXPECT_STREQ(LengthUnitName(LengthUnit::kCentimetre), "cm");
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
