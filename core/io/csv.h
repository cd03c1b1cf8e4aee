#pragma once
// A small CSV reader and writer helpers for photopose's tables (docs/formats.md).
//
// Reading: comma separator; a field may be enclosed in double quotes, inside which commas and line
// breaks are literal and "" stands for one quote; spaces and tabs around a field are trimmed (kept
// inside quotes); empty lines and lines whose first non-blank character is '#' are skipped; the
// first remaining line is the header. Header names are matched case-insensitively and, with
// CsvOptions::tolerant_header, also with spaces and underscores removed ("Point ID", "point_id" and
// "POINTID" all name PointID). Every problem is a Status whose message reads
// "file:line: column: what is wrong", with 1-based physical line numbers of the file.
//
// Input is bounded (docs/formats.md, "Limits and refusals"): only regular files or "-" (standard
// input) are read, at most kMaxInputBytes of UTF-8 text without NUL or other control characters,
// lines of at most kMaxLineBytes, rows of at most kMaxColumns fields. Messages escape every byte
// that is not printable UTF-8 (EscapeForMessage), so a message is always one clean line.

#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "core/status.h"

namespace photopose {

// Largest input file (bytes): a marks table of a million marks is about 60 MB.
constexpr size_t kMaxInputBytes = size_t{256} << 20;
// Longest physical line (bytes) of any text input.
constexpr size_t kMaxLineBytes = size_t{64} << 10;
// Most fields of a CSV header or row: the camera table, the widest, has 32 standard columns.
constexpr size_t kMaxColumns = 1000;

struct CsvOptions {
  // Also match header names with spaces and underscores removed.
  bool tolerant_header = false;
};

// One data row: its fields, one per header column, trimmed and unquoted.
struct CsvRow {
  int line = 0;  // 1-based line of the file where the row starts
  std::vector<std::string> fields;
};

// A column of a table's schema looked up once in a header (CsvHeader::Column), so that reading a
// field of a row is an index, not a look-up by name: `name` is the schema's name, for messages.
struct CsvColumn {
  static constexpr size_t kAbsent = static_cast<size_t>(-1);
  std::string_view name;
  size_t index = kAbsent;  // in the header; kAbsent when the header lacks the column
  bool present() const { return index != kAbsent; }
};

// The header of a CSV text: its column names, how names are matched, and the file name and line
// that messages give.
class CsvHeader {
 public:
  const std::string& file_name() const { return file_name_; }
  int header_line() const { return header_line_; }
  const std::vector<std::string>& header() const { return header_; }

  // Index of the column called `name` (matched as described above), or nullopt.
  std::optional<size_t> ColumnIndex(std::string_view name) const;
  // The column called `name`, to read many rows by.
  CsvColumn Column(std::string_view name) const;
  bool HasColumn(std::string_view name) const { return ColumnIndex(name).has_value(); }
  // Whether two header names name the same column under this table's matching rules.
  bool SameName(std::string_view a, std::string_view b) const;
  // "file:header_line: <name>: required column is missing" for the first name not in the header.
  Status RequireColumns(const std::vector<std::string_view>& names) const;
  // Indices of the header columns that are none of `known`, in header order.
  std::vector<size_t> ColumnsOtherThan(const std::vector<std::string_view>& known) const;
  // Status::Error("file:line: column: what"); the column part is left out when `column` is empty.
  Status Error(int line, std::string_view column, std::string_view what) const;

 private:
  friend class CsvReader;
  std::string Normalized(std::string_view name) const;
  // Takes the header fields; "column N: the header names no column here" and "column appears
  // twice in the header" otherwise.
  Status SetNames(std::vector<std::string> names);

  std::string file_name_;
  CsvOptions options_;
  int header_line_ = 0;
  std::vector<std::string> header_;
  // Normalized header name -> column index: lookups and the duplicate check stay linear in the
  // number of columns.
  std::unordered_map<std::string, size_t> column_by_name_;
};

// Reads CSV text row by row without copying it: each field is a view into the text (a quoted field
// holding "" or a line break is unescaped into a buffer of the reader), valid until the next row.
// The parse is the one CsvTable makes, with the same messages; this is the way to read a table of
// millions of rows.
class CsvReader {
 public:
  // Checks the text (CheckTextInput) and reads its header. `text` and `file_name` must outlive the
  // reader.
  Status Open(std::string_view text, const std::string& file_name, const CsvOptions& options);

  const CsvHeader& header() const { return header_; }
  // At most this many data rows are left (one per remaining line): enough to reserve for.
  size_t MaxRows() const;

  // Reads the next data row; *has_row is false at the end of the text. A row with another number
  // of fields than the header is an error ("file:line: row has 3 fields but the header has 2").
  Status Next(bool* has_row);
  // The current row: the line it starts on and its fields, one per header column.
  int line() const { return row_line_; }
  const std::vector<std::string_view>& fields() const { return fields_; }

  // Calls `read_row(const CsvRowReader&)` for every data row left; stops at the first error.
  template <typename ReadRow>
  Status ForEachRow(ReadRow read_row);

 private:
  // Skips empty and comment lines; false at the end of the text.
  bool NextRecordStart();
  // Parses one record at the current position into fields_; `header` names the columns in
  // messages (false for the header itself).
  Status ParseRecord(bool header);
  Status ParseField(bool header, size_t index, std::string_view* field);
  std::string ColumnName(bool header, size_t index) const;

  std::string_view text_;
  const std::string* file_name_ = nullptr;
  size_t pos_ = 0;
  int line_ = 1;
  int row_line_ = 0;
  CsvHeader header_;
  std::vector<std::string_view> fields_;
  // Unescaped quoted fields of the current row, and (field, offset, size) of each in it.
  std::string unescaped_;
  struct UnescapedField {
    size_t field, offset, size;
  };
  std::vector<UnescapedField> unescaped_fields_;
};

// A whole table in memory: the header and every row as strings. Fine for small tables (cameras,
// fiducials); large ones are read with CsvReader.
class CsvTable : public CsvHeader {
 public:
  // Reads and parses the file at `path`; `path` names the file in messages. A file that cannot be
  // opened gives "path: cannot open: <system reason>".
  static Status Read(const std::string& path, const CsvOptions& options, CsvTable* table);
  // Parses CSV text; `file_name` names it in messages.
  static Status Parse(std::string_view text, const std::string& file_name,
                      const CsvOptions& options, CsvTable* table);

  const std::vector<CsvRow>& rows() const { return rows_; }

 private:
  std::vector<CsvRow> rows_;
};

// Typed, checked access to the fields of one row. `column` is the schema's name of a column, or
// the column looked up once (CsvHeader::Column) when many rows are read; a column absent from the
// header reads as an empty field. Every error reads "file:line: column: what is wrong".
class CsvRowReader {
 public:
  // A row of a table.
  CsvRowReader(const CsvTable& table, const CsvRow& row);
  // The current row of a reader (valid until its next row).
  explicit CsvRowReader(const CsvReader& reader)
      : header_(reader.header()), line_(reader.line()), fields_(&reader.fields()) {}
  CsvRowReader(const CsvRowReader&) = delete;
  CsvRowReader& operator=(const CsvRowReader&) = delete;

  const CsvHeader& header() const { return header_; }
  int line() const { return line_; }
  // The field's text; empty when the column is absent.
  std::string_view Text(const CsvColumn& column) const {
    return column.index < fields_->size() ? (*fields_)[column.index] : std::string_view();
  }
  std::string_view Text(std::string_view column) const { return Text(header_.Column(column)); }
  // Whether the column is present and its field is not empty.
  bool Has(const CsvColumn& column) const { return !Text(column).empty(); }
  bool Has(std::string_view column) const { return !Text(column).empty(); }

  // A non-empty field ("column: is empty" otherwise).
  Status RequiredText(const CsvColumn& column, std::string* value) const;
  // A finite number; an empty field gives nullopt.
  Status Number(const CsvColumn& column, std::optional<double>* value) const;
  // A finite number; an empty field is an error.
  Status RequiredNumber(const CsvColumn& column, double* value) const;
  // A whole number; an empty field gives nullopt.
  Status Integer(const CsvColumn& column, std::optional<long long>* value) const;
  // Finite numbers separated by spaces and/or semicolons; an empty field gives an empty list.
  Status NumberList(const CsvColumn& column, std::vector<double>* values) const;
  // Groups separated by semicolons, each of `group_size` finite numbers separated by spaces
  // ("x y;x y;..."), flattened into `values`; an empty field gives an empty list.
  Status NumberGroups(const CsvColumn& column, int group_size, std::vector<double>* values) const;

  // The same by the column's name.
  Status RequiredText(std::string_view column, std::string* value) const {
    return RequiredText(header_.Column(column), value);
  }
  Status Number(std::string_view column, std::optional<double>* value) const {
    return Number(header_.Column(column), value);
  }
  Status RequiredNumber(std::string_view column, double* value) const {
    return RequiredNumber(header_.Column(column), value);
  }
  Status Integer(std::string_view column, std::optional<long long>* value) const {
    return Integer(header_.Column(column), value);
  }
  Status NumberList(std::string_view column, std::vector<double>* values) const {
    return NumberList(header_.Column(column), values);
  }
  Status NumberGroups(std::string_view column, int group_size, std::vector<double>* values) const {
    return NumberGroups(header_.Column(column), group_size, values);
  }

  // Status::Error("file:line: column: what").
  Status Error(std::string_view column, std::string_view what) const {
    return header_.Error(line_, column, what);
  }
  Status Error(const CsvColumn& column, std::string_view what) const {
    return header_.Error(line_, column.name, what);
  }

 private:
  const CsvHeader& header_;
  int line_;
  std::vector<std::string_view> table_fields_;  // views of a CsvTable row's fields
  const std::vector<std::string_view>* fields_;
};

template <typename ReadRow>
Status CsvReader::ForEachRow(ReadRow read_row) {
  bool has_row = false;
  while (true) {
    PHOTOPOSE_RETURN_IF_ERROR(Next(&has_row));
    if (!has_row) return Status::Ok();
    PHOTOPOSE_RETURN_IF_ERROR(read_row(CsvRowReader(*this)));
  }
}

// Reads a whole input into *text: a regular file, or standard input for "-". Anything else (a
// folder, a device such as /dev/zero, a FIFO, a socket) is refused without reading or waiting (it
// is opened non-blocking and checked on the open descriptor), and so is an input of more than
// kMaxInputBytes, by its size or by what it holds when read. The file is read, never mapped: one
// that shrinks or grows while it is read gives the text it held then (a mapping would die of
// SIGBUS). Every reader of core/io gets its files here. Errors: "path: cannot open: <system reason>",
// "path: cannot read: <system reason>", "path: is a character device, not a regular file ...",
// "path: is larger than 268435456 bytes ...". Messages name standard input "<stdin>".
Status ReadTextFile(const std::string& path, std::string* text);
// The name of an input in messages: the path as given, "<stdin>" for "-".
std::string InputName(const std::string& path);

// Checks that `text` is text photopose reads: UTF-8 (a UTF-8 byte order mark is allowed; UTF-16
// and UTF-32 byte order marks are recognised and named), no NUL or other control character but
// tab, line feed and carriage return, no line longer than kMaxLineBytes. Errors are located:
// "file:line: character N: byte 0xFF is not UTF-8; photopose reads UTF-8 text".
Status CheckTextInput(std::string_view text, const std::string& file_name);

// `text` fit for a one-line message: control characters, DEL and bytes that are not UTF-8 are
// written as \xHH (tab, line feed and carriage return as \t, \n, \r); everything else is kept.
// Escaping an escaped text changes nothing.
std::string EscapeForMessage(std::string_view text);
// Most characters of a token (a field, a word of a file) that a message repeats.
constexpr size_t kMaxEchoedCharacters = 40;
// A token of the input as a message repeats it: escaped as EscapeForMessage does, and cut after
// kMaxEchoedCharacters characters with "…(N bytes)" giving its whole size, so that a message
// stays a line however long the token ("0000000000000000000000000000000000000000…(1048576
// bytes)").
std::string TokenForMessage(std::string_view token);
// A name (an image, a point, a camera) as a message quotes it: 'name', escaped as
// EscapeForMessage does, never cut (two long names that differ at the end stay told apart).
std::string QuotedForMessage(std::string_view name);
// Where a one-line message points: "file:line: column: ", the line left out when unknown (0 or
// less), the column when empty.
std::string WhereInFile(std::string_view file, int line, std::string_view column = {});

// Parses a whole field as a finite decimal number (C locale, a leading '+' allowed). On failure
// returns false and sets *why to a phrase about the text ("'abc' is not a number",
// "'nan' is not a finite number", "'1e999' is out of range").
bool ParseFiniteNumber(std::string_view text, double* value, std::string* why);
// Parses a whole field as a whole number ("12", "+1", also "12.0"). Same failure contract.
bool ParseWholeNumber(std::string_view text, long long* value, std::string* why);
// Splits text at runs of white space (spaces, tabs, line ends), dropping empty words.
std::vector<std::string_view> SplitWords(std::string_view text);
// Lower case with spaces and underscores removed: how the tables compare header names (tolerant)
// and enumerated values ("Distortion Model" = "DistortionModel", "x_right_y_up" = "X_RIGHT_Y_UP").
std::string FoldedName(std::string_view text);

// The items of a comma-separated value (a flag's list), each trimmed of blanks; an empty item stays
// as an empty string so that callers can name it ("a,,b" -> "a", "", "b"; "" -> none).
std::vector<std::string> SplitCommaList(const std::string& text);

// Splits a list field at semicolons and runs of spaces/tabs; an empty item between two semicolons
// is returned as an empty string so that callers can report it.
std::vector<std::string_view> SplitListItems(std::string_view text);

// The shortest decimal text that reads back as exactly the same double.
std::string FormatNumber(double value);
// Appends FormatNumber(value) to *text (no string of its own).
void AppendFormattedNumber(double value, std::string* text);
// For messages: whole numbers below 1e15 in plain digits ("100000000", not "1e+08"), anything
// else as FormatNumber.
std::string FormatPlainNumber(double value);
// Numbers joined by semicolons, each as FormatNumber.
std::string FormatNumberList(const std::vector<double>& values);
// A field as it must appear in a CSV line: quoted when it holds a comma, a quote, a line break,
// leading or trailing blanks, or starts with '#'.
std::string CsvQuote(std::string_view field);
// Appends CsvQuote(field) to *text.
void AppendCsvField(std::string_view field, std::string* text);
// Fields quoted and joined by commas, with a trailing '\n'.
std::string CsvLine(const std::vector<std::string>& fields);

}  // namespace photopose
