#pragma once
// Fast reading and writing of the whitespace-separated text formats of other tools (COLMAP text
// models, BAL problems, Bundler .out files, DBAT lists): the whole file is read once (ReadTextFile
// of core/io/csv.h: regular files only, at most kMaxInputBytes), lines and
// tokens are views into it (no string per row), numbers are parsed and printed with
// std::from_chars / std::to_chars (shortest text that reads back as the same double). Every parse
// error is a Status whose message reads "file:line: field: what is wrong", escaped, with the tokens
// it repeats cut (TokenForMessage).

#include <cstdint>
#include <string>
#include <string_view>

#include "core/io/csv.h"
#include "core/status.h"

namespace photopose {

// "file:line: field: what" (field left out when empty; line left out when 0).
Status TextError(const std::string& file, int line, std::string_view field, std::string_view what);

// The physical lines of a text, numbered from 1, without their line end ("\n" or "\r\n").
class TextLines {
 public:
  explicit TextLines(std::string_view text) : text_(text) {}
  // The next line and its 1-based number; false at the end of the text.
  bool Next(std::string_view* line, int* line_number);

 private:
  std::string_view text_;
  size_t position_ = 0;
  int line_number_ = 0;
};

// Tokens separated by blanks (spaces, tabs, carriage returns, line ends; optionally commas) of a
// piece of text: one line of a line-based format, or a whole file for a token-stream format (BAL),
// in which case line() follows the line ends crossed.
class TokenScanner {
 public:
  // `file` names the text in messages and must outlive the scanner; `first_line` is the line
  // number of the first character of `text`.
  TokenScanner(std::string_view text, const std::string& file, int first_line,
               bool comma_separates = false)
      : text_(text), file_(file), line_(first_line), comma_separates_(comma_separates) {}

  // The line of the next token (after skipping blanks), or of the end of the text.
  int line();
  // True when only blanks are left.
  bool AtEnd();
  // The rest of the text with the blanks around it removed (e.g. a name with spaces).
  std::string_view Rest();

  // The next token; "field: is missing" at the end of the text.
  Status Word(std::string_view field, std::string_view* word) {
    SkipBlanks();
    // At the end of a text, the line of the last token is where something is missing.
    if (position_ >= text_.size())
      return TextError(file_, last_token_line_ > 0 ? last_token_line_ : line_, field, "is missing");
    const size_t start = position_;
    while (position_ < text_.size() && !IsSeparator(text_[position_])) ++position_;
    *word = text_.substr(start, position_ - start);
    last_token_line_ = line_;
    return Status::Ok();
  }
  // The next token as a finite number / a whole number.
  Status Number(std::string_view field, double* value);
  Status Integer(std::string_view field, long long* value);
  // A whole number in [min, max].
  Status IntegerIn(std::string_view field, long long min, long long max, long long* value);
  // A finite number in [-max_magnitude, max_magnitude] ("'1e+300' is outside [-100000000,
  // 100000000] m", `unit` after the range when not empty).
  Status NumberWithin(std::string_view field, double max_magnitude, std::string_view unit,
                      double* value);

  // "file:line: field: what" at the current line (field left out when empty).
  Status Error(std::string_view field, std::string_view what);

 private:
  bool IsSeparator(char c) const {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f' ||
           (comma_separates_ && c == ',');
  }
  void SkipBlanks() {
    while (position_ < text_.size() && IsSeparator(text_[position_])) {
      if (text_[position_] == '\n') ++line_;
      ++position_;
    }
  }

  std::string_view text_;
  const std::string& file_;
  size_t position_ = 0;
  int line_;
  int last_token_line_ = 0;
  bool comma_separates_;
};


// Whether a line holds nothing but blanks, or a comment ('#' as its first non-blank character).
bool IsBlankOrComment(std::string_view line);

// Calls `row(TokenScanner*)` for every line of `text` that is neither blank nor a comment, with a
// scanner of that line (commas separate too when `comma_separates`); `path` names the text in
// messages. Stops at the first error `row` returns.
template <typename Row>
Status ForEachRecordLine(std::string_view text, const std::string& path, bool comma_separates,
                         Row row);
// The same for the file at `path`.
template <typename Row>
Status ForEachRecordLineOfFile(const std::string& path, bool comma_separates, Row row) {
  std::string text;
  PHOTOPOSE_RETURN_IF_ERROR(ReadTextFile(path, &text));
  return ForEachRecordLine(text, InputName(path), comma_separates, row);
}

// Appends the shortest decimal text that reads back as exactly `value` (std::to_chars).
void AppendNumber(double value, std::string* text);
void AppendInteger(long long value, std::string* text);

template <typename Row>
Status ForEachRecordLine(std::string_view text, const std::string& path, bool comma_separates,
                         Row row) {
  TextLines lines(text);
  std::string_view line;
  int line_number = 0;
  while (lines.Next(&line, &line_number)) {
    if (IsBlankOrComment(line)) continue;
    TokenScanner scanner(line, path, line_number, comma_separates);
    PHOTOPOSE_RETURN_IF_ERROR(row(&scanner));
  }
  return Status::Ok();
}

}  // namespace photopose
