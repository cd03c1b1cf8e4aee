#include "core/csv.h"

#include <sys/stat.h>

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>

namespace photopose {
namespace {

bool IsBlank(char c) { return c == ' ' || c == '\t'; }

std::string_view TrimBlanks(std::string_view s) {
  while (!s.empty() && (IsBlank(s.front()) || s.front() == '\r')) s.remove_prefix(1);
  while (!s.empty() && (IsBlank(s.back()) || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

// Splits at `separator`, keeping empty parts.
std::vector<std::string_view> SplitOn(std::string_view text, char separator) {
  std::vector<std::string_view> parts;
  size_t start = 0;
  while (true) {
    const size_t end = text.find(separator, start);
    if (end == std::string_view::npos) {
      parts.push_back(text.substr(start));
      return parts;
    }
    parts.push_back(text.substr(start, end - start));
    start = end + 1;
  }
}

std::string Quoted(std::string_view text) { return "'" + std::string(text) + "'"; }

// The record parser: walks the text once, keeping the physical line number.
class CsvParser {
 public:
  CsvParser(std::string_view text, const std::string& file_name)
      : text_(text), file_name_(file_name) {
    if (text_.substr(0, 3) == "\xEF\xBB\xBF") pos_ = 3;  // UTF-8 byte order mark
  }

  // Skips empty and comment lines; false at the end of the text.
  bool NextRecordStart() {
    while (pos_ < text_.size()) {
      size_t i = pos_;
      while (i < text_.size() && (IsBlank(text_[i]) || text_[i] == '\r')) ++i;
      if (i < text_.size() && text_[i] != '\n' && text_[i] != '#') return true;
      const size_t end = text_.find('\n', i);
      if (end == std::string_view::npos) {
        pos_ = text_.size();
        return false;
      }
      pos_ = end + 1;
      ++line_;
    }
    return false;
  }

  // Parses one record starting at the current position. `header` names the columns in messages
  // (null for the header itself).
  Status ParseRecord(const std::vector<std::string>* header, CsvRow* row) {
    row->line = line_;
    row->fields.clear();
    while (true) {
      std::string field;
      PHOTOPOSE_RETURN_IF_ERROR(ParseField(header, row->fields.size(), &field));
      row->fields.push_back(std::move(field));
      if (pos_ < text_.size() && text_[pos_] == ',') {
        ++pos_;
        continue;
      }
      if (pos_ < text_.size()) {  // at '\n'
        ++pos_;
        ++line_;
      }
      return Status::Ok();
    }
  }

 private:
  std::string ColumnName(const std::vector<std::string>* header, size_t index) const {
    if (header != nullptr && index < header->size()) return (*header)[index];
    return "field " + std::to_string(index + 1);
  }

  Status ParseField(const std::vector<std::string>* header, size_t index, std::string* field) {
    while (pos_ < text_.size() && IsBlank(text_[pos_])) ++pos_;
    if (pos_ < text_.size() && text_[pos_] == '"') {
      const int quote_line = line_;
      ++pos_;
      while (true) {
        if (pos_ >= text_.size()) {
          return Status::Error(file_name_ + ":" + std::to_string(quote_line) + ": " +
                               ColumnName(header, index) + ": quoted field is not closed");
        }
        const char c = text_[pos_++];
        if (c == '"') {
          if (pos_ < text_.size() && text_[pos_] == '"') {
            field->push_back('"');
            ++pos_;
            continue;
          }
          break;
        }
        if (c == '\n') {
          ++line_;
          if (!field->empty() && field->back() == '\r') field->pop_back();
        }
        field->push_back(c);
      }
      while (pos_ < text_.size() && (IsBlank(text_[pos_]) || text_[pos_] == '\r')) ++pos_;
      if (pos_ < text_.size() && text_[pos_] != ',' && text_[pos_] != '\n') {
        return Status::Error(file_name_ + ":" + std::to_string(line_) + ": " +
                             ColumnName(header, index) + ": text after the closing quote");
      }
      return Status::Ok();
    }
    const size_t start = pos_;
    while (pos_ < text_.size() && text_[pos_] != ',' && text_[pos_] != '\n') ++pos_;
    *field = std::string(TrimBlanks(text_.substr(start, pos_ - start)));
    return Status::Ok();
  }

  std::string_view text_;
  const std::string& file_name_;
  size_t pos_ = 0;
  int line_ = 1;
};

}  // namespace

// ------------------------------------------------------------------ CsvTable

Status CsvTable::Read(const std::string& path, const CsvOptions& options, CsvTable* table) {
  std::string text;
  PHOTOPOSE_RETURN_IF_ERROR(ReadTextFile(path, &text));
  return Parse(text, path, options, table);
}

Status CsvTable::Parse(std::string_view text, const std::string& file_name,
                       const CsvOptions& options, CsvTable* table) {
  CsvTable result;
  result.file_name_ = file_name;
  result.options_ = options;
  CsvParser parser(text, file_name);
  if (!parser.NextRecordStart()) return Status::Error(file_name + ": no header line");

  CsvRow header_row;
  PHOTOPOSE_RETURN_IF_ERROR(parser.ParseRecord(nullptr, &header_row));
  result.header_line_ = header_row.line;
  result.header_ = std::move(header_row.fields);
  for (size_t i = 0; i < result.header_.size(); ++i) {
    const std::string& name = result.header_[i];
    if (name.empty()) {
      return result.Error(result.header_line_, "column " + std::to_string(i + 1),
                          "the header names no column here");
    }
    std::string normalized = result.Normalized(name);
    for (size_t j = 0; j < i; ++j) {
      if (result.normalized_header_[j] == normalized) {
        return result.Error(
            result.header_line_, name,
            "column appears twice in the header (also as '" + result.header_[j] + "')");
      }
    }
    result.normalized_header_.push_back(std::move(normalized));
  }

  while (parser.NextRecordStart()) {
    CsvRow row;
    PHOTOPOSE_RETURN_IF_ERROR(parser.ParseRecord(&result.header_, &row));
    if (row.fields.size() != result.header_.size()) {
      return result.Error(row.line, "",
                          "row has " + std::to_string(row.fields.size()) +
                              " fields but the header has " +
                              std::to_string(result.header_.size()));
    }
    result.rows_.push_back(std::move(row));
  }
  *table = std::move(result);
  return Status::Ok();
}

std::string CsvTable::Normalized(std::string_view name) const {
  if (options_.tolerant_header) return FoldedName(name);
  std::string lower(name);
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return lower;
}

bool CsvTable::SameName(std::string_view a, std::string_view b) const {
  return Normalized(a) == Normalized(b);
}

std::optional<size_t> CsvTable::ColumnIndex(std::string_view name) const {
  const std::string normalized = Normalized(name);
  for (size_t i = 0; i < normalized_header_.size(); ++i) {
    if (normalized_header_[i] == normalized) return i;
  }
  return std::nullopt;
}

Status CsvTable::RequireColumns(const std::vector<std::string_view>& names) const {
  for (const std::string_view name : names) {
    if (!HasColumn(name)) return Error(header_line_, name, "required column is missing");
  }
  return Status::Ok();
}

std::vector<size_t> CsvTable::ColumnsOtherThan(const std::vector<std::string_view>& known) const {
  std::vector<size_t> others;
  for (size_t i = 0; i < header_.size(); ++i) {
    bool is_known = false;
    for (const std::string_view name : known) is_known = is_known || SameName(header_[i], name);
    if (!is_known) others.push_back(i);
  }
  return others;
}

Status CsvTable::Error(int line, std::string_view column, std::string_view what) const {
  std::string message = file_name_ + ":" + std::to_string(line) + ": ";
  if (!column.empty()) message += std::string(column) + ": ";
  message += what;
  return Status::Error(std::move(message));
}

// ------------------------------------------------------------------ CsvRowReader

std::string_view CsvRowReader::Text(std::string_view column) const {
  const std::optional<size_t> index = table_.ColumnIndex(column);
  if (!index || *index >= row_.fields.size()) return {};
  return row_.fields[*index];
}

Status CsvRowReader::RequiredText(std::string_view column, std::string* value) const {
  const std::string_view text = Text(column);
  if (text.empty()) return Error(column, "is empty");
  *value = std::string(text);
  return Status::Ok();
}

Status CsvRowReader::Number(std::string_view column, std::optional<double>* value) const {
  const std::string_view text = Text(column);
  value->reset();
  if (text.empty()) return Status::Ok();
  double number = 0.0;
  std::string why;
  if (!ParseFiniteNumber(text, &number, &why)) return Error(column, why);
  *value = number;
  return Status::Ok();
}

Status CsvRowReader::RequiredNumber(std::string_view column, double* value) const {
  std::optional<double> number;
  PHOTOPOSE_RETURN_IF_ERROR(Number(column, &number));
  if (!number) return Error(column, "is empty");
  *value = *number;
  return Status::Ok();
}

Status CsvRowReader::Integer(std::string_view column, std::optional<long long>* value) const {
  const std::string_view text = Text(column);
  value->reset();
  if (text.empty()) return Status::Ok();
  long long number = 0;
  std::string why;
  if (!ParseWholeNumber(text, &number, &why)) return Error(column, why);
  *value = number;
  return Status::Ok();
}

Status CsvRowReader::NumberList(std::string_view column, std::vector<double>* values) const {
  values->clear();
  const std::vector<std::string_view> items = SplitListItems(Text(column));
  for (size_t i = 0; i < items.size(); ++i) {
    const std::string item_name = "item " + std::to_string(i + 1);
    if (items[i].empty()) return Error(column, item_name + " is empty");
    double number = 0.0;
    std::string why;
    if (!ParseFiniteNumber(items[i], &number, &why)) return Error(column, item_name + ": " + why);
    values->push_back(number);
  }
  return Status::Ok();
}

Status CsvRowReader::NumberGroups(std::string_view column, int group_size,
                                  std::vector<double>* values) const {
  values->clear();
  const std::string_view text = Text(column);
  if (text.empty()) return Status::Ok();
  const std::vector<std::string_view> groups = SplitOn(text, ';');
  for (size_t g = 0; g < groups.size(); ++g) {
    const std::string group_name = "item " + std::to_string(g + 1);
    const std::vector<std::string_view> words = SplitWords(TrimBlanks(groups[g]));
    if (words.size() != static_cast<size_t>(group_size)) {
      return Error(column, group_name + " " + Quoted(TrimBlanks(groups[g])) + " has " +
                               std::to_string(words.size()) + " numbers, expected " +
                               std::to_string(group_size) + " separated by spaces");
    }
    for (const std::string_view word : words) {
      double number = 0.0;
      std::string why;
      if (!ParseFiniteNumber(word, &number, &why)) return Error(column, group_name + ": " + why);
      values->push_back(number);
    }
  }
  return Status::Ok();
}

// ------------------------------------------------------------------ free functions

Status ReadTextFile(const std::string& path, std::string* text) {
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) return Status::Error(path + ": cannot open: " + std::strerror(errno));
  text->clear();
  // One allocation for a regular file (a large table is read without regrowing the buffer).
  struct stat info;
  if (fstat(fileno(file.get()), &info) == 0 && S_ISREG(info.st_mode) && info.st_size > 0)
    text->reserve(static_cast<size_t>(info.st_size));
  char buffer[1 << 16];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof(buffer), file.get())) > 0) text->append(buffer, n);
  // fopen succeeds on a folder; the read then fails with EISDIR.
  if (std::ferror(file.get()))
    return Status::Error(path + ": cannot read: " + std::strerror(errno));
  return Status::Ok();
}

bool ParseFiniteNumber(std::string_view text, double* value, std::string* why) {
  std::string_view digits = text;
  // from_chars takes no '+'; accept one before a digit or a point ("+1", "+.5").
  if (digits.size() > 1 && digits[0] == '+' &&
      (std::isdigit(static_cast<unsigned char>(digits[1])) || digits[1] == '.')) {
    digits.remove_prefix(1);
  }
  double number = 0.0;
  const char* end = digits.data() + digits.size();
  const std::from_chars_result result =
      std::from_chars(digits.data(), end, number, std::chars_format::general);
  if (result.ec == std::errc::result_out_of_range && result.ptr == end) {
    *why = Quoted(text) + " is out of range";
    return false;
  }
  if (result.ec != std::errc() || result.ptr != end || digits.empty()) {
    *why = Quoted(text) + " is not a number";
    return false;
  }
  if (!std::isfinite(number)) {
    *why = Quoted(text) + " is not a finite number";
    return false;
  }
  *value = number;
  return true;
}

bool ParseWholeNumber(std::string_view text, long long* value, std::string* why) {
  std::string_view digits = text;
  if (digits.size() > 1 && digits[0] == '+' && std::isdigit(static_cast<unsigned char>(digits[1])))
    digits.remove_prefix(1);
  long long number = 0;
  const char* end = digits.data() + digits.size();
  const std::from_chars_result result = std::from_chars(digits.data(), end, number);
  if (result.ec == std::errc() && result.ptr == end && !digits.empty()) {
    *value = number;
    return true;
  }
  // "12.0" or "1e3" as written by some spreadsheets.
  double real = 0.0;
  if (!ParseFiniteNumber(text, &real, why)) return false;
  if (real != std::floor(real)) {
    *why = Quoted(text) + " is not a whole number";
    return false;
  }
  constexpr double kLimit = 9.2e18;  // inside the range of long long
  if (std::abs(real) > kLimit) {
    *why = Quoted(text) + " is out of range";
    return false;
  }
  *value = static_cast<long long>(real);
  return true;
}

std::vector<std::string_view> SplitWords(std::string_view text) {
  std::vector<std::string_view> words;
  const auto is_space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && is_space(text[i])) ++i;
    const size_t start = i;
    while (i < text.size() && !is_space(text[i])) ++i;
    if (i > start) words.push_back(text.substr(start, i - start));
  }
  return words;
}

std::string FoldedName(std::string_view text) {
  std::string folded;
  for (const char c : text) {
    if (c == ' ' || c == '_') continue;
    folded.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  }
  return folded;
}

std::vector<std::string_view> SplitListItems(std::string_view text) {
  std::vector<std::string_view> items;
  text = TrimBlanks(text);
  if (text.empty()) return items;
  for (const std::string_view part : SplitOn(text, ';')) {
    const std::vector<std::string_view> words = SplitWords(part);
    if (words.empty()) items.push_back({});
    items.insert(items.end(), words.begin(), words.end());
  }
  return items;
}

std::string FormatNumber(double value) {
  char buffer[64];
  const std::to_chars_result result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

std::string FormatNumberList(const std::vector<double>& values) {
  std::string text;
  for (size_t i = 0; i < values.size(); ++i) {
    if (i > 0) text += ';';
    text += FormatNumber(values[i]);
  }
  return text;
}

std::string CsvQuote(std::string_view field) {
  const bool needs_quotes =
      field.find_first_of(",\"\n\r") != std::string_view::npos ||
      (!field.empty() && (IsBlank(field.front()) || IsBlank(field.back()) || field.front() == '#'));
  if (!needs_quotes) return std::string(field);
  std::string quoted = "\"";
  for (const char c : field) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  quoted += '"';
  return quoted;
}

std::string CsvLine(const std::vector<std::string>& fields) {
  // A single empty field would make an empty line, which readers skip.
  if (fields.size() == 1 && fields[0].empty()) return "\"\"\n";
  std::string line;
  for (size_t i = 0; i < fields.size(); ++i) {
    if (i > 0) line += ',';
    line += CsvQuote(fields[i]);
  }
  line += '\n';
  return line;
}

}  // namespace photopose
