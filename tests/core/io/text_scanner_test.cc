#include "core/io/text_scanner.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "tests/support/temp_dir.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// Every line of a text with its number.
std::vector<std::pair<int, std::string>> AllLines(std::string_view text) {
  TextLines lines(text);
  std::vector<std::pair<int, std::string>> out;
  std::string_view line;
  int number = 0;
  while (lines.Next(&line, &number)) out.emplace_back(number, std::string(line));
  return out;
}

TEST(TextLines, NumbersLinesFromOneAndDropsBothLineEnds) {
  const auto lines = AllLines("a b\r\nc\n\nlast");
  const std::vector<std::pair<int, std::string>> expected = {
      {1, "a b"}, {2, "c"}, {3, ""}, {4, "last"}};
  EXPECT_EQ(lines, expected);
  // A final line end does not make an empty last line; an empty text has no line.
  EXPECT_EQ(AllLines("x\n").size(), 1u);
  EXPECT_TRUE(AllLines("").empty());
  // A lone carriage return inside a line is kept (only "\r\n" is a line end).
  EXPECT_EQ(AllLines("a\rb\n")[0].second, "a\rb");
}

TEST(TokenScanner, ReadsWordsNumbersAndIntegersInOrder) {
  const std::string file = "model.txt";
  TokenScanner scanner(" 7  PINHOLE\t-1.5e3 42 ", file, 12);
  long long id = 0;
  std::string_view model;
  double value = 0.0;
  long long count = 0;
  ASSERT_TRUE(scanner.Integer("CAMERA_ID", &id).ok());
  ASSERT_TRUE(scanner.Word("MODEL", &model).ok());
  ASSERT_TRUE(scanner.Number("PARAM", &value).ok());
  ASSERT_TRUE(scanner.IntegerIn("COUNT", 0, 100, &count).ok());
  EXPECT_EQ(id, 7);
  EXPECT_EQ(model, "PINHOLE");
  EXPECT_EQ(value, -1500.0);
  EXPECT_EQ(count, 42);
  EXPECT_TRUE(scanner.AtEnd());
  EXPECT_EQ(scanner.line(), 12);
}

TEST(TokenScanner, ErrorsNameTheFileLineAndField) {
  const std::string file = "images.txt";
  TokenScanner scanner("1 x", file, 5);
  long long id = 0;
  ASSERT_TRUE(scanner.Integer("IMAGE_ID", &id).ok());
  double qw = 0.0;
  const Status not_a_number = scanner.Number("QW", &qw);
  ASSERT_FALSE(not_a_number.ok());
  EXPECT_EQ(not_a_number.message().rfind("images.txt:5: QW: ", 0), 0u) << not_a_number.message();
  // At the end: missing, at the line of the last token.
  std::string_view word;
  const Status missing = scanner.Word("NAME", &word);
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.message(), "images.txt:5: NAME: is missing");
  // Out of range, with the range.
  TokenScanner range("101", file, 9);
  long long count = 0;
  const Status outside = range.IntegerIn("COUNT", 0, 100, &count);
  ASSERT_FALSE(outside.ok());
  EXPECT_EQ(outside.message(), "images.txt:9: COUNT: 101 is out of range [0, 100]");
  // Not a whole number; not finite.
  TokenScanner fraction("2.5 inf", file, 1);
  EXPECT_FALSE(fraction.Integer("N", &count).ok());
  EXPECT_FALSE(fraction.Number("X", &qw).ok());
}

TEST(TokenScanner, AWholeFileFollowsItsLineEnds) {
  // A token stream over several lines (BAL): line() is the line of the next token.
  const std::string file = "problem.txt";
  TokenScanner scanner("1 2\n\n  3\n4", file, 1);
  long long value = 0;
  ASSERT_TRUE(scanner.Integer("a", &value).ok());
  ASSERT_TRUE(scanner.Integer("b", &value).ok());
  EXPECT_EQ(scanner.line(), 3);
  ASSERT_TRUE(scanner.Integer("c", &value).ok());
  EXPECT_EQ(value, 3);
  EXPECT_EQ(scanner.line(), 4);
  ASSERT_TRUE(scanner.Integer("d", &value).ok());
  EXPECT_TRUE(scanner.AtEnd());
  // Something missing after the last token is reported at that token's line.
  EXPECT_EQ(scanner.Integer("e", &value).message(), "problem.txt:4: e: is missing");
}

TEST(TokenScanner, CommasSeparateOnlyWhenAsked) {
  const std::string file = "list.csv";
  std::string_view word;
  TokenScanner with_commas("a,b , c", file, 1, /*comma_separates=*/true);
  std::vector<std::string> words;
  while (!with_commas.AtEnd()) {
    ASSERT_TRUE(with_commas.Word("w", &word).ok());
    words.emplace_back(word);
  }
  EXPECT_EQ(words, (std::vector<std::string>{"a", "b", "c"}));
  TokenScanner without("a,b", file, 1);
  ASSERT_TRUE(without.Word("w", &word).ok());
  EXPECT_EQ(word, "a,b");
}

TEST(TokenScanner, RestIsTheRemainingTextTrimmed) {
  const std::string file = "images.txt";
  TokenScanner scanner("3 image name with spaces.jpg \r", file, 1);
  long long id = 0;
  ASSERT_TRUE(scanner.Integer("IMAGE_ID", &id).ok());
  EXPECT_EQ(scanner.Rest(), "image name with spaces.jpg");
}

TEST(TextError, LeavesOutAnEmptyFieldAndLineZero) {
  EXPECT_EQ(TextError("f", 3, "X", "bad").message(), "f:3: X: bad");
  EXPECT_EQ(TextError("f", 3, "", "bad").message(), "f:3: bad");
  EXPECT_EQ(TextError("f", 0, "X", "bad").message(), "f: X: bad");
}

TEST(IsBlankOrComment, BlanksAndHashCommentsOnly) {
  EXPECT_TRUE(IsBlankOrComment(""));
  EXPECT_TRUE(IsBlankOrComment(" \t\r"));
  EXPECT_TRUE(IsBlankOrComment("  # a comment"));
  EXPECT_FALSE(IsBlankOrComment(" 1 # not a comment line"));
  EXPECT_FALSE(IsBlankOrComment("x"));
}

TEST(ForEachRecordLine, SkipsBlanksAndCommentsAndStopsAtTheFirstError) {
  const std::string path = "points3D.txt";
  const std::string text = "# header\n1 2\n\n   \n3 4\nx 5\n6 7\n";
  std::vector<std::pair<int, long long>> rows;  // line, first value
  const Status status =
      ForEachRecordLine(text, path, /*comma_separates=*/false, [&](TokenScanner* s) {
        const int line = s->line();
        long long value = 0;
        PHOTOPOSE_RETURN_IF_ERROR(s->Integer("POINT3D_ID", &value));
        rows.emplace_back(line, value);
        return Status::Ok();
      });
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message().rfind("points3D.txt:6: POINT3D_ID: ", 0), 0u) << status.message();
  // Lines 2 and 5 were read; the comment (1), the blank lines (3, 4) were not; line 7 was not
  // reached.
  const std::vector<std::pair<int, long long>> expected = {{2, 1}, {5, 3}};
  EXPECT_EQ(rows, expected);
}

TEST(AppendNumber, ShortestTextThatReadsBackExactly) {
  for (const double value : {0.0, 1.0, -2.5, 0.1, 1.0 / 3.0, 6.02214076e23, 5e-324,
                             std::numeric_limits<double>::max()}) {
    std::string text;
    AppendNumber(value, &text);
    EXPECT_EQ(std::strtod(text.c_str(), nullptr), value) << text;
  }
  // Shortest: 0.1 is "0.1", not 0.1000000000000000055511151231257827.
  std::string text = "x=";
  AppendNumber(0.1, &text);
  EXPECT_EQ(text, "x=0.1");
  AppendInteger(-9007199254740993LL, &text);
  EXPECT_EQ(text, "x=0.1-9007199254740993");
}

TEST(ForEachRecordLineOfFile, ReadsAFileUnderTheInputRules) {
  const testing::ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  std::vector<std::string> words;
  const auto collect = [&](TokenScanner* scanner) {
    std::string_view word;
    while (!scanner->AtEnd()) {
      PHOTOPOSE_RETURN_IF_ERROR(scanner->Word("word", &word));
      words.emplace_back(word);
    }
    return Status::Ok();
  };
  ASSERT_TRUE(ForEachRecordLineOfFile(dir.Write("a.txt", "1 2\n# note\n3 4\n"), false, collect).ok());
  EXPECT_EQ(words, (std::vector<std::string>{"1", "2", "3", "4"}));
  const Status missing = ForEachRecordLineOfFile(dir.Path("none.txt"), false, collect);
  EXPECT_EQ(missing.message().rfind(dir.Path("none.txt") + ": cannot open: ", 0), 0u)
      << missing.message();
  // A folder is refused (only regular files and standard input are read).
  EXPECT_EQ(ForEachRecordLineOfFile(dir.path(), false, collect).message(),
            dir.path() +
                ": is a folder, not a regular file; photopose reads regular files, or standard "
                "input for '-'");
}

TEST(TokenScannerTest, NumbersBeyondTheirBoundAreRefusedAndLongTokensCut) {
  const std::string file = "f.txt";
  const std::string text = "12 -1e300 " + std::string(1 << 20, '7') + "x";
  TokenScanner scanner(text, file, 3);
  double value = 0.0;
  ASSERT_TRUE(scanner.NumberWithin("a", 100.0, "m", &value).ok());
  EXPECT_EQ(value, 12.0);
  EXPECT_EQ(scanner.NumberWithin("b", 100.0, "m", &value).message(),
            "f.txt:3: b: '-1e300' is outside [-100, 100] m");
  // A megabyte token is echoed as 40 characters and its size.
  EXPECT_EQ(scanner.NumberWithin("c", 100.0, "", &value).message(),
            "f.txt:3: c: '" + std::string(40, '7') + "\u2026(1048577 bytes)' is not a number");
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
