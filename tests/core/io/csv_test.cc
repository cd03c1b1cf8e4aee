#include "core/io/csv.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

constexpr CsvOptions kStrict{/*tolerant_header=*/false};
constexpr CsvOptions kTolerant{/*tolerant_header=*/true};

CsvTable ParseOrDie(const std::string& text, const CsvOptions& options = kStrict) {
  CsvTable table;
  const Status status = CsvTable::Parse(text, "t.csv", options, &table);
  EXPECT_TRUE(status.ok()) << status.message();
  return table;
}

std::string ParseError(const std::string& text, const CsvOptions& options = kStrict) {
  CsvTable table;
  const Status status = CsvTable::Parse(text, "t.csv", options, &table);
  EXPECT_FALSE(status.ok());
  return status.message();
}

TEST(CsvTest, ParsesHeaderAndRowsWithLineNumbers) {
  const CsvTable table = ParseOrDie(
      "# a comment before the header\n"
      "PointID, X ,Y\n"
      "\n"
      "P1,1.5,2\n"
      "   # an indented comment\n"
      "  P2 ,\t3 , 4  \n");
  EXPECT_EQ(table.header_line(), 2);
  EXPECT_EQ(table.header(), (std::vector<std::string>{"PointID", "X", "Y"}));
  ASSERT_EQ(table.rows().size(), 2u);
  EXPECT_EQ(table.rows()[0].line, 4);
  EXPECT_EQ(table.rows()[0].fields, (std::vector<std::string>{"P1", "1.5", "2"}));
  EXPECT_EQ(table.rows()[1].line, 6);
  EXPECT_EQ(table.rows()[1].fields, (std::vector<std::string>{"P2", "3", "4"}));
}

TEST(CsvTest, QuotedFieldsKeepCommasQuotesBlanksAndLineBreaks) {
  const CsvTable table = ParseOrDie(
      "A,B,C\n"
      "\"x, y\", \"say \"\"hi\"\"\" ,\"  padded  \"\n"
      "\"two\nlines\",\"\",#not a comment\n"
      "last,row,here\n");
  ASSERT_EQ(table.rows().size(), 3u);
  EXPECT_EQ(table.rows()[0].fields, (std::vector<std::string>{"x, y", "say \"hi\"", "  padded  "}));
  EXPECT_EQ(table.rows()[1].line, 3);
  EXPECT_EQ(table.rows()[1].fields, (std::vector<std::string>{"two\nlines", "", "#not a comment"}));
  EXPECT_EQ(table.rows()[2].line, 5);  // the quoted line break counts as a line
}

TEST(CsvTest, HandlesCrLfByteOrderMarkAndMissingFinalNewline) {
  const CsvTable ok = ParseOrDie("\xEF\xBB\xBFName,Value\r\na,1\r\n\r\nb,\"2\"");
  EXPECT_EQ(ok.header()[0], "Name");
  ASSERT_EQ(ok.rows().size(), 2u);
  EXPECT_EQ(ok.rows()[0].fields, (std::vector<std::string>{"a", "1"}));
  EXPECT_EQ(ok.rows()[1].line, 4);
  EXPECT_EQ(ok.rows()[1].fields, (std::vector<std::string>{"b", "2"}));
}

TEST(CsvTest, EmptyTrailingFieldIsKept) {
  const CsvTable table = ParseOrDie("A,B,C\n1,,\n");
  EXPECT_EQ(table.rows()[0].fields, (std::vector<std::string>{"1", "", ""}));
}

TEST(CsvTest, HeaderLookupIsCaseInsensitive) {
  const CsvTable table = ParseOrDie("pointid,FOCAL LENGTH\nP,1\n");
  EXPECT_EQ(table.ColumnIndex("PointID"), std::optional<size_t>(0));
  EXPECT_EQ(table.ColumnIndex("Focal Length"), std::optional<size_t>(1));
  EXPECT_FALSE(table.HasColumn("FocalLength"));  // strict: spaces matter
  EXPECT_FALSE(table.HasColumn("Z"));
}

TEST(CsvTest, TolerantHeaderIgnoresSpacesAndUnderscores) {
  const CsvTable table = ParseOrDie("Point ID,focal_length,n rows\nP,1,2\n", kTolerant);
  EXPECT_EQ(table.ColumnIndex("PointID"), std::optional<size_t>(0));
  EXPECT_EQ(table.ColumnIndex("FocalLength"), std::optional<size_t>(1));
  EXPECT_EQ(table.ColumnIndex("NRows"), std::optional<size_t>(2));
  EXPECT_TRUE(table.SameName("Point_ID", "pointid"));
}

TEST(CsvTest, ReportsMalformedText) {
  EXPECT_EQ(ParseError(""), "t.csv: no header line");
  EXPECT_EQ(ParseError("# only a comment\n\n"), "t.csv: no header line");
  EXPECT_EQ(ParseError("A,B\n1,2,3\n"), "t.csv:2: row has 3 fields but the header has 2");
  EXPECT_EQ(ParseError("A,B\n\n1\n"), "t.csv:3: row has 1 fields but the header has 2");
  EXPECT_EQ(ParseError("A,B\n1,\"open\n2,3\n"), "t.csv:2: B: quoted field is not closed");
  EXPECT_EQ(ParseError("A,B\n1,\"x\"y\n"), "t.csv:2: B: text after the closing quote");
  EXPECT_EQ(ParseError("A,,C\n"), "t.csv:1: column 2: the header names no column here");
  EXPECT_EQ(ParseError("X,Y,x\n"), "t.csv:1: x: column appears twice in the header (also as 'X')");
  EXPECT_EQ(ParseError("Point ID,PointID\n", kTolerant),
            "t.csv:1: PointID: column appears twice in the header (also as 'Point ID')");
}

TEST(CsvTest, MissingFileNamesTheSystemReason) {
  CsvTable table;
  const Status status = CsvTable::Read("/nonexistent/dir/points.csv", kStrict, &table);
  EXPECT_EQ(status.message(),
            "/nonexistent/dir/points.csv: cannot open: No such file or directory");
}

TEST(CsvTest, RequireColumnsNamesTheFirstMissing) {
  const CsvTable table = ParseOrDie("# c\nPointID,X,Y\n");
  EXPECT_TRUE(table.RequireColumns({"PointID", "X"}).ok());
  EXPECT_EQ(table.RequireColumns({"PointID", "Z", "W"}).message(),
            "t.csv:2: Z: required column is missing");
}

TEST(CsvTest, ColumnsOtherThanKeepsHeaderOrder) {
  const CsvTable table = ParseOrDie("Z,Note,X,Extra\n1,a,2,b\n");
  EXPECT_EQ(table.ColumnsOtherThan({"X", "Y", "Z"}), (std::vector<size_t>{1, 3}));
}

TEST(CsvReaderTest, StreamsRowsAsViewsWithTheTableParse) {
  const std::string text =
      "\xEF\xBB\xBFName, Value ,Note\r\n"
      "# comment\r\n"
      "P1 , 1.5,\"a \"\"b\"\"\"\r\n"
      "\r\n"
      "\"P2\",2,\"two\r\nlines\"\r\n"
      "P3,x,plain";
  const std::string name = "t.csv";
  CsvReader reader;
  ASSERT_TRUE(reader.Open(text, name, kTolerant).ok());
  EXPECT_EQ(reader.header().header(), (std::vector<std::string>{"Name", "Value", "Note"}));
  EXPECT_EQ(reader.header().header_line(), 1);
  EXPECT_EQ(reader.MaxRows(), 6u);  // a bound: one per line left
  const CsvColumn value = reader.header().Column("value");
  EXPECT_EQ(value.index, 1u);
  EXPECT_FALSE(reader.header().Column("Other").present());
  std::vector<int> lines;
  std::vector<std::vector<std::string>> rows;
  const Status status = reader.ForEachRow([&](const CsvRowReader& row) {
    lines.push_back(row.line());
    rows.emplace_back(row.header().header().size());
    for (size_t i = 0; i < rows.back().size(); ++i)
      rows.back()[i] = std::string(row.Text(CsvColumn{"", i}));
    double number = 0.0;
    return row.RequiredNumber(value, &number);
  });
  EXPECT_EQ(status.message(), "t.csv:7: value: 'x' is not a number");
  EXPECT_EQ(lines, (std::vector<int>{3, 5, 7}));
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"P1", "1.5", "a \"b\""}));
  EXPECT_EQ(rows[1], (std::vector<std::string>{"P2", "2", "two\nlines"}));
  EXPECT_EQ(rows[2], (std::vector<std::string>{"P3", "x", "plain"}));
  // Fields that need no unescaping are views into the text itself.
  CsvReader again;
  ASSERT_TRUE(again.Open(text, name, kTolerant).ok());
  bool has_row = false;
  ASSERT_TRUE(again.Next(&has_row).ok());
  ASSERT_TRUE(has_row);
  EXPECT_GE(again.fields()[0].data(), text.data());
  EXPECT_LT(again.fields()[0].data(), text.data() + text.size());
}

TEST(CsvRowReaderTest, ReadsTypedFields) {
  const CsvTable table = ParseOrDie(
      "Name,Value,Count,List,Pairs,Empty\n"
      "P7,+1.5e3,12,1; 2 3;4,1 2;3 4,\n");
  const CsvRowReader row(table, table.rows()[0]);
  std::string name;
  ASSERT_TRUE(row.RequiredText("name", &name).ok());
  EXPECT_EQ(name, "P7");
  double value = 0.0;
  ASSERT_TRUE(row.RequiredNumber("Value", &value).ok());
  EXPECT_EQ(value, 1500.0);
  std::optional<long long> count;
  ASSERT_TRUE(row.Integer("Count", &count).ok());
  EXPECT_EQ(count, 12);
  std::vector<double> list;
  ASSERT_TRUE(row.NumberList("List", &list).ok());
  EXPECT_EQ(list, (std::vector<double>{1, 2, 3, 4}));
  ASSERT_TRUE(row.NumberGroups("Pairs", 2, &list).ok());
  EXPECT_EQ(list, (std::vector<double>{1, 2, 3, 4}));
  std::optional<double> empty = 5.0;
  ASSERT_TRUE(row.Number("Empty", &empty).ok());
  EXPECT_FALSE(empty.has_value());
  ASSERT_TRUE(row.Number("AbsentColumn", &empty).ok());
  EXPECT_FALSE(empty.has_value());
  ASSERT_TRUE(row.NumberList("Empty", &list).ok());
  EXPECT_TRUE(list.empty());
  EXPECT_FALSE(row.Has("Empty"));
  EXPECT_TRUE(row.Has("Name"));
}

TEST(CsvRowReaderTest, ErrorsNameFileLineAndColumn) {
  const CsvTable table = ParseOrDie(
      "PointID,X,Y,Z,N,L,P\n"
      "\n"
      "P1,nan,inf,abc,1.5,1;;2,1 2;3\n");
  const CsvRowReader row(table, table.rows()[0]);
  double value = 0.0;
  std::optional<long long> count;
  std::vector<double> list;
  std::string text;
  EXPECT_EQ(row.RequiredNumber("Z", &value).message(), "t.csv:3: Z: 'abc' is not a number");
  EXPECT_EQ(row.RequiredNumber("X", &value).message(), "t.csv:3: X: 'nan' is not a finite number");
  EXPECT_EQ(row.RequiredNumber("Y", &value).message(), "t.csv:3: Y: 'inf' is not a finite number");
  EXPECT_EQ(row.RequiredNumber("W", &value).message(), "t.csv:3: W: is empty");
  EXPECT_EQ(row.RequiredText("W", &text).message(), "t.csv:3: W: is empty");
  EXPECT_EQ(row.Integer("N", &count).message(), "t.csv:3: N: '1.5' is not a whole number");
  EXPECT_EQ(row.NumberList("L", &list).message(), "t.csv:3: L: item 2 is empty");
  EXPECT_EQ(row.NumberGroups("P", 2, &list).message(),
            "t.csv:3: P: item 2 '3' has 1 numbers, expected 2 separated by spaces");
}

TEST(ParseFiniteNumberTest, AcceptsDecimalNumbersOnly) {
  double value = 0.0;
  std::string why;
  EXPECT_TRUE(ParseFiniteNumber("-12.5", &value, &why));
  EXPECT_EQ(value, -12.5);
  EXPECT_TRUE(ParseFiniteNumber("+.5", &value, &why));
  EXPECT_EQ(value, 0.5);
  EXPECT_TRUE(ParseFiniteNumber("6378137", &value, &why));
  EXPECT_EQ(value, 6378137.0);
  EXPECT_TRUE(ParseFiniteNumber("1e-5", &value, &why));
  EXPECT_EQ(value, 1e-5);
  for (const char* bad : {"", "+", "-", "1.5x", "1 2", "0x10", "1,5", "++1", "e5"}) {
    EXPECT_FALSE(ParseFiniteNumber(bad, &value, &why)) << bad;
    EXPECT_EQ(why, "'" + std::string(bad) + "' is not a number");
  }
  for (const char* bad : {"nan", "NaN", "inf", "-Infinity"}) {
    EXPECT_FALSE(ParseFiniteNumber(bad, &value, &why)) << bad;
    EXPECT_EQ(why, "'" + std::string(bad) + "' is not a finite number");
  }
  EXPECT_FALSE(ParseFiniteNumber("1e999", &value, &why));
  EXPECT_EQ(why, "'1e999' is out of range");
}

TEST(ParseWholeNumberTest, AcceptsIntegersAndWholeReals) {
  long long value = 0;
  std::string why;
  EXPECT_TRUE(ParseWholeNumber("+1", &value, &why));
  EXPECT_EQ(value, 1);
  EXPECT_TRUE(ParseWholeNumber("-1", &value, &why));
  EXPECT_EQ(value, -1);
  EXPECT_TRUE(ParseWholeNumber("17310.0", &value, &why));
  EXPECT_EQ(value, 17310);
  EXPECT_FALSE(ParseWholeNumber("2.5", &value, &why));
  EXPECT_EQ(why, "'2.5' is not a whole number");
  EXPECT_FALSE(ParseWholeNumber("1e30", &value, &why));
  EXPECT_EQ(why, "'1e30' is out of range");
  EXPECT_FALSE(ParseWholeNumber("one", &value, &why));
  EXPECT_EQ(why, "'one' is not a number");
}

TEST(SplitListItemsTest, SplitsAtSemicolonsAndBlanks) {
  EXPECT_EQ(SplitListItems("1;2 3 ;  4"), (std::vector<std::string_view>{"1", "2", "3", "4"}));
  EXPECT_TRUE(SplitListItems("   ").empty());
  EXPECT_EQ(SplitListItems("1;;2"), (std::vector<std::string_view>{"1", "", "2"}));
}

TEST(SplitCommaListTest, TrimsItemsKeepsEmptyOnesDropsAFinalComma) {
  using List = std::vector<std::string>;
  EXPECT_EQ(SplitCommaList("a, b ,\tc"), (List{"a", "b", "c"}));
  EXPECT_EQ(SplitCommaList("a,,b"), (List{"a", "", "b"}));
  EXPECT_EQ(SplitCommaList("a, "), (List{"a", ""}));
  EXPECT_EQ(SplitCommaList("a,"), (List{"a"}));
  EXPECT_EQ(SplitCommaList(","), (List{""}));
  EXPECT_TRUE(SplitCommaList("").empty());
}

TEST(FormatNumberTest, RoundTripsEveryDouble) {
  const std::vector<double> values = {0.0,
                                      -0.0,
                                      1.0 / 3.0,
                                      100500.0,
                                      -120.0,
                                      1e-300,
                                      6.02e23,
                                      0.1,
                                      std::nextafter(1.0, 2.0),
                                      std::numeric_limits<double>::max()};
  for (const double v : values) {
    double back = 0.0;
    std::string why;
    ASSERT_TRUE(ParseFiniteNumber(FormatNumber(v), &back, &why)) << why;
    EXPECT_EQ(back, v) << FormatNumber(v);
  }
  EXPECT_EQ(FormatNumber(100500.0), "100500");
  EXPECT_EQ(FormatNumber(0.1), "0.1");
  EXPECT_EQ(FormatNumberList({1, -2.5, 3}), "1;-2.5;3");
  EXPECT_EQ(FormatNumberList({}), "");
}

TEST(CsvWriteTest, QuotesOnlyWhatNeedsIt) {
  EXPECT_EQ(CsvQuote("plain"), "plain");
  EXPECT_EQ(CsvQuote("a,b"), "\"a,b\"");
  EXPECT_EQ(CsvQuote("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(CsvQuote(" padded"), "\" padded\"");
  EXPECT_EQ(CsvQuote("#1"), "\"#1\"");
  EXPECT_EQ(CsvQuote("two\nlines"), "\"two\nlines\"");
  EXPECT_EQ(CsvLine({"a", "", "b,c"}), "a,,\"b,c\"\n");
  EXPECT_EQ(CsvLine({""}), "\"\"\n");
}

TEST(CsvWriteTest, WrittenLinesReadBack) {
  const std::vector<std::string> fields = {"#id", " spaced ", "a,b", "q\"q", "multi\nline", ""};
  const std::string text = CsvLine({"A", "B", "C", "D", "E", "F"}) + CsvLine(fields);
  const CsvTable table = ParseOrDie(text);
  ASSERT_EQ(table.rows().size(), 1u);
  EXPECT_EQ(table.rows()[0].fields, fields);
}

// ------------------------------------------------------------------ bounded input

TEST(CsvInputTest, ByteOrderMarksOtherThanUtf8AreNamed) {
  const std::string text = "A\n1\n";
  EXPECT_EQ(ParseError(std::string("\xFF\xFE", 2) + "A\0\n\0", kStrict),
            "t.csv: is UTF-16 (little-endian byte order mark); photopose reads UTF-8 text: save "
            "the file as UTF-8");
  EXPECT_EQ(ParseError(std::string("\xFE\xFF\0A", 4)),
            "t.csv: is UTF-16 (big-endian byte order mark); photopose reads UTF-8 text: save the "
            "file as UTF-8");
  EXPECT_EQ(ParseError(std::string("\xFF\xFE\0\0A\0\0\0", 8)),
            "t.csv: is UTF-32 (little-endian byte order mark); photopose reads UTF-8 text: save "
            "the file as UTF-8");
  EXPECT_EQ(ParseError(std::string("\0\0\xFE\xFF", 4)),
            "t.csv: is UTF-32 (big-endian byte order mark); photopose reads UTF-8 text: save the "
            "file as UTF-8");
  EXPECT_EQ(ParseOrDie("\xEF\xBB\xBF" + text).header()[0], "A");  // UTF-8's is fine
}

TEST(CsvInputTest, BinaryAndNonUtf8BytesAreLocatedAndEscaped) {
  EXPECT_EQ(ParseError(std::string("A,B\n1,x\0y\n", 10)),
            "t.csv:2: character 4: NUL byte: photopose reads UTF-8 text (is this a binary file, "
            "or UTF-16 without a byte order mark?)");
  EXPECT_EQ(ParseError("A,B\n1,\x1b[31m\n"),
            "t.csv:2: character 3: control character 0x1B: photopose reads plain UTF-8 text");
  EXPECT_EQ(ParseError("A,B\nx,\xFF\n"),
            "t.csv:2: character 3: byte 0xFF is not UTF-8; photopose reads UTF-8 text");
  // Overlong form, surrogate, beyond U+10FFFF, a sequence cut short.
  for (const std::string bad : {"\xC0\xAF", "\xED\xA0\x80", "\xF4\x90\x80\x80", "\xE2\x82"}) {
    EXPECT_EQ(ParseError("A\n" + bad + "\n").rfind("t.csv:2: character 1: byte 0x", 0), 0u);
  }
  // Valid UTF-8 of every length, tabs and CR LF are text.
  const CsvTable table = ParseOrDie("Name,Note\r\nK\xC3\xB6ln,\xE2\x82\xAC\t\xF0\x9F\x93\xB7\r\n");
  EXPECT_EQ(table.rows()[0].fields[0], "K\xC3\xB6ln");
}

TEST(CsvInputTest, LinesAndColumnsAreBounded) {
  const std::string long_line(kMaxLineBytes + 1, 'x');
  EXPECT_EQ(ParseError("A\n" + long_line + "\n"),
            "t.csv:2: the line is longer than 65536 bytes, the longest line photopose reads");
  EXPECT_TRUE(CheckTextInput("A\n" + long_line.substr(1) + "\n", "t.csv").ok());
  std::string header, row;
  for (size_t i = 0; i <= kMaxColumns; ++i) {
    header += (i ? ",C" : "C") + std::to_string(i);
    row += i ? ",1" : "1";
  }
  EXPECT_EQ(ParseError(header + "\n"),
            "t.csv:1: the header has more than 1000 fields; photopose reads at most 1000 columns");
  const size_t last_comma = header.rfind(',');
  EXPECT_EQ(ParseError(header.substr(0, last_comma) + "\n" + row + "\n"),
            "t.csv:2: the row has more than 1000 fields; photopose reads at most 1000 columns");
  // The widest table that is allowed reads, and a duplicate far to the right is found.
  const CsvTable wide =
      ParseOrDie(header.substr(0, last_comma) + "\n" + row.substr(0, row.rfind(',')) + "\n");
  EXPECT_EQ(wide.ColumnIndex("C999"), std::optional<size_t>(999));
  EXPECT_EQ(ParseError(header.substr(0, last_comma - 5) + ",C7\n"),
            "t.csv:1: C7: column appears twice in the header (also as 'C7')");
}

TEST(CsvInputTest, OnlyRegularFilesAreRead) {
  std::string text = "unchanged";
  EXPECT_EQ(ReadTextFile("/dev/zero", &text).message(),
            "/dev/zero: is a character device, not a regular file; photopose reads regular files, "
            "or standard input for '-'");
  EXPECT_TRUE(text.empty());
  const std::string folder = ::testing::TempDir();
  EXPECT_EQ(ReadTextFile(folder, &text).message(),
            folder +
                ": is a folder, not a regular file; photopose reads regular files, or "
                "standard input for '-'");
  // A FIFO is refused at once, without waiting for a writer.
  const std::string fifo = ::testing::TempDir() + "/photopose_csv_fifo_" + std::to_string(getpid());
  ASSERT_EQ(mkfifo(fifo.c_str(), 0644), 0);
  EXPECT_EQ(ReadTextFile(fifo, &text).message(),
            fifo +
                ": is a FIFO (named pipe), not a regular file; photopose reads regular files, "
                "or standard input for '-'");
  unlink(fifo.c_str());
}

TEST(CsvInputTest, FilesLargerThanTheLimitAreRefusedWithoutReading) {
  const std::string path = ::testing::TempDir() + "/photopose_csv_big_" + std::to_string(getpid());
  std::ofstream(path) << "A\n";
  std::filesystem::resize_file(path, kMaxInputBytes + 1);  // sparse: costs no disk space
  std::string text;
  EXPECT_EQ(ReadTextFile(path, &text).message(),
            path + ": is larger than 268435456 bytes, the largest input photopose reads");
  std::filesystem::remove(path);
}

TEST(CsvInputTest, StandardInputIsReadForADashAndNamedInMessages) {
  int pipe_fds[2];
  ASSERT_EQ(pipe(pipe_fds), 0);
  const std::string text = "PointID,X\nP1,abc\n";
  ASSERT_EQ(write(pipe_fds[1], text.data(), text.size()), static_cast<ssize_t>(text.size()));
  close(pipe_fds[1]);
  const int saved = dup(STDIN_FILENO);
  dup2(pipe_fds[0], STDIN_FILENO);
  close(pipe_fds[0]);
  CsvTable table;
  const Status status = CsvTable::Read("-", kStrict, &table);
  dup2(saved, STDIN_FILENO);
  close(saved);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(table.file_name(), "<stdin>");
  EXPECT_EQ(table.rows()[0].fields[1], "abc");
  double value = 0.0;
  EXPECT_EQ(CsvRowReader(table, table.rows()[0]).RequiredNumber("X", &value).message(),
            "<stdin>:2: X: 'abc' is not a number");
}

TEST(EscapeForMessageTest, EscapesControlsAndNonUtf8OnlyAndIsIdempotent) {
  using namespace std::string_literals;
  const std::string raw = "a\0b\x1b[1m\t\n\r\x7f\xff K\xC3\xB6ln \\x41"s;
  const std::string escaped = EscapeForMessage(raw);
  EXPECT_EQ(escaped, "a\\x00b\\x1B[1m\\t\\n\\r\\x7F\\xFF K\xC3\xB6ln \\x41");
  EXPECT_EQ(EscapeForMessage(escaped), escaped);
  // Field text echoed in a message is escaped too.
  const CsvTable table = ParseOrDie("A\n\"two\nlines\"\n");
  double value = 0.0;
  EXPECT_EQ(CsvRowReader(table, table.rows()[0]).RequiredNumber("A", &value).message(),
            "t.csv:2: A: 'two\\nlines' is not a number");
}

TEST(MessagePlaceTest, QuotesANameEscapedAndWholeAndNamesFileLineColumn) {
  const std::string long_name(60, 'x');
  // A name is never cut (two long names that differ at their end stay told apart); a token is.
  EXPECT_EQ(QuotedForMessage(long_name + "1"), "'" + long_name + "1'");
  EXPECT_NE(TokenForMessage(long_name + "1"), long_name + "1");
  EXPECT_EQ(QuotedForMessage("IMG\t1\n"), "'IMG\\t1\\n'");
  EXPECT_EQ(WhereInFile("marks.csv", 12, "Row"), "marks.csv:12: Row: ");
  EXPECT_EQ(WhereInFile("marks.csv", 12), "marks.csv:12: ");
  EXPECT_EQ(WhereInFile("cameras.csv", 0, "ApplyECC"), "cameras.csv: ApplyECC: ");
  EXPECT_EQ(WhereInFile("cameras.csv", -1), "cameras.csv: ");
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
