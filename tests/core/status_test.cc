#include "core/status.h"

#include <gtest/gtest.h>

#include <string>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

TEST(Status, OkAndErrorCarryTheirOutcomeAndMessage) {
  EXPECT_TRUE(Status().ok());
  EXPECT_TRUE(Status::Ok().ok());
  EXPECT_EQ(Status::Ok().message(), "");
  const Status error = Status::Error("points.csv:3: X: is missing");
  EXPECT_FALSE(error.ok());
  EXPECT_EQ(error.message(), "points.csv:3: X: is missing");
  // An error without words is still an error: success is not read from the message.
  EXPECT_FALSE(Status::Error("").ok());
}

// Counts how far it got: 1 after the first step, 2 after the second.
Status TwoSteps(const Status& first, const Status& second, int* steps) {
  *steps = 0;
  PHOTOPOSE_RETURN_IF_ERROR(first);
  *steps = 1;
  PHOTOPOSE_RETURN_IF_ERROR(second);
  *steps = 2;
  return Status::Ok();
}

TEST(Status, ReturnIfErrorStopsAtTheFirstErrorAndPassesItOn) {
  int steps = -1;
  EXPECT_TRUE(TwoSteps(Status::Ok(), Status::Ok(), &steps).ok());
  EXPECT_EQ(steps, 2);
  const Status first = TwoSteps(Status::Error("first"), Status::Error("second"), &steps);
  EXPECT_FALSE(first.ok());
  EXPECT_EQ(first.message(), "first");
  EXPECT_EQ(steps, 0);
  const Status second = TwoSteps(Status::Ok(), Status::Error("second"), &steps);
  EXPECT_EQ(second.message(), "second");
  EXPECT_EQ(steps, 1);
}

// The XxxOptions convention: bool IsValid(std::string* why).
struct ScaleOptions {
  double scale = 1.0;
  bool IsValid(std::string* why) const {
    if (scale > 0.0) return true;
    *why = "the scale must be positive";
    return false;
  }
};

TEST(Status, InvalidBecauseGivesTheReasonWhereAskedAndSaysNo) {
  std::string why = "before";
  EXPECT_FALSE(InvalidBecause(&why, "x must be >= 0"));
  EXPECT_EQ(why, "x must be >= 0");
  // Without a place for the reason it still says no.
  EXPECT_FALSE(InvalidBecause(nullptr, "x must be >= 0"));
}

TEST(Status, ValidateTurnsIsValidIntoAStatusWithItsReason) {
  ScaleOptions options;
  EXPECT_TRUE(Validate(options).ok());
  EXPECT_TRUE(Validate(options, "invalid options: ").ok());
  options.scale = -1.0;
  EXPECT_FALSE(Validate(options).ok());
  EXPECT_EQ(Validate(options).message(), "the scale must be positive");
  EXPECT_EQ(Validate(options, "invalid options: ").message(),
            "invalid options: the scale must be positive");
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
