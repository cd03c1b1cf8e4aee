#include "core/io/csv.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>

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

std::string QuotedToken(std::string_view text) { return "'" + TokenForMessage(text) + "'"; }

// Length of the UTF-8 sequence that starts at text[i] (1 to 4), or 0 when the bytes there are not
// well-formed UTF-8 (RFC 3629: no overlong forms, no surrogates, nothing above U+10FFFF).
size_t Utf8SequenceLength(std::string_view text, size_t i) {
  const auto byte = [&](size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char c = byte(i);
  if (c < 0x80) return 1;
  size_t length;
  unsigned char low = 0x80, high = 0xBF;  // range of the second byte
  if (c >= 0xC2 && c <= 0xDF) {
    length = 2;
  } else if (c >= 0xE0 && c <= 0xEF) {
    length = 3;
    if (c == 0xE0) low = 0xA0;   // overlong
    if (c == 0xED) high = 0x9F;  // surrogates
  } else if (c >= 0xF0 && c <= 0xF4) {
    length = 4;
    if (c == 0xF0) low = 0x90;   // overlong
    if (c == 0xF4) high = 0x8F;  // above U+10FFFF
  } else {
    return 0;
  }
  if (i + length > text.size()) return 0;
  if (byte(i + 1) < low || byte(i + 1) > high) return 0;
  for (size_t k = 2; k < length; ++k)
    if ((byte(i + k) & 0xC0) != 0x80) return 0;
  return length;
}

std::string HexByte(unsigned char c) {
  static const char kDigits[] = "0123456789ABCDEF";
  return std::string("0x") + kDigits[c >> 4] + kDigits[c & 15];
}

// What a file-system node that is not a regular file is, for messages.
const char* NodeKind(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

// Reads everything from `fd` into *text, up to limit + 1 bytes (one more than allowed shows the
// excess), straight into the string: `expected` (the size fstat gave, 0 when unknown) is read in one
// piece, and a file that shrinks or grows meanwhile is read as it is then, never past the limit.
// Waits on a non-blocking descriptor instead of spinning.
bool ReadAtMost(int fd, size_t limit, size_t expected, std::string* text, int* error_number) {
  constexpr size_t kChunk = size_t{1} << 16;
  size_t size = 0;
  text->clear();
  while (size <= limit) {
    if (size == text->size())
      text->resize(std::min(limit + 1, std::max({size + kChunk, 2 * size, expected + 1})));
    const ssize_t n = read(fd, text->data() + size, text->size() - size);
    if (n > 0) {
      size += static_cast<size_t>(n);
    } else if (n == 0) {
      break;
    } else if (errno == EINTR) {
      continue;
    } else if (errno == EAGAIN || errno == EWOULDBLOCK) {
      pollfd wait{fd, POLLIN, 0};
      poll(&wait, 1, -1);
    } else {
      *error_number = errno;
      return false;
    }
  }
  text->resize(size);
  return true;
}

}  // namespace

// ------------------------------------------------------------------ CsvHeader

Status CsvHeader::SetNames(std::vector<std::string> names) {
  header_ = std::move(names);
  column_by_name_.clear();
  for (size_t i = 0; i < header_.size(); ++i) {
    const std::string& name = header_[i];
    if (name.empty())
      return Error(header_line_, "column " + std::to_string(i + 1), "the header names no column here");
    const auto [first, inserted] = column_by_name_.emplace(Normalized(name), i);
    if (!inserted) {
      return Error(header_line_, name,
                   "column appears twice in the header (also as " +
                       QuotedToken(header_[first->second]) + ")");
    }
  }
  return Status::Ok();
}

std::string CsvHeader::Normalized(std::string_view name) const {
  if (options_.tolerant_header) return FoldedName(name);
  std::string lower(name);
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return lower;
}

bool CsvHeader::SameName(std::string_view a, std::string_view b) const {
  return Normalized(a) == Normalized(b);
}

std::optional<size_t> CsvHeader::ColumnIndex(std::string_view name) const {
  const auto found = column_by_name_.find(Normalized(name));
  if (found == column_by_name_.end()) return std::nullopt;
  return found->second;
}

CsvColumn CsvHeader::Column(std::string_view name) const {
  return CsvColumn{name, ColumnIndex(name).value_or(CsvColumn::kAbsent)};
}

Status CsvHeader::RequireColumns(const std::vector<std::string_view>& names) const {
  for (const std::string_view name : names) {
    if (!HasColumn(name)) return Error(header_line_, name, "required column is missing");
  }
  return Status::Ok();
}

std::vector<size_t> CsvHeader::ColumnsOtherThan(const std::vector<std::string_view>& known) const {
  std::vector<size_t> others;
  for (size_t i = 0; i < header_.size(); ++i) {
    bool is_known = false;
    for (const std::string_view name : known) is_known = is_known || SameName(header_[i], name);
    if (!is_known) others.push_back(i);
  }
  return others;
}

Status CsvHeader::Error(int line, std::string_view column, std::string_view what) const {
  std::string message = file_name_ + ":" + std::to_string(line) + ": ";
  if (!column.empty()) message += std::string(column) + ": ";
  message += what;
  return Status::Error(EscapeForMessage(message));
}

// ------------------------------------------------------------------ CsvReader

Status CsvReader::Open(std::string_view text, const std::string& file_name,
                       const CsvOptions& options) {
  PHOTOPOSE_RETURN_IF_ERROR(CheckTextInput(text, file_name));
  text_ = text;
  file_name_ = &file_name;
  pos_ = text_.substr(0, 3) == "\xEF\xBB\xBF" ? 3 : 0;  // UTF-8 byte order mark
  line_ = 1;
  header_ = CsvHeader();
  header_.file_name_ = file_name;
  header_.options_ = options;
  if (!NextRecordStart()) return Status::Error(EscapeForMessage(file_name) + ": no header line");
  PHOTOPOSE_RETURN_IF_ERROR(ParseRecord(/*header=*/true));
  header_.header_line_ = row_line_;
  return header_.SetNames(std::vector<std::string>(fields_.begin(), fields_.end()));
}

size_t CsvReader::MaxRows() const {
  return static_cast<size_t>(std::count(text_.begin() + pos_, text_.end(), '\n')) + 1;
}

Status CsvReader::Next(bool* has_row) {
  *has_row = NextRecordStart();
  if (!*has_row) return Status::Ok();
  PHOTOPOSE_RETURN_IF_ERROR(ParseRecord(/*header=*/false));
  if (fields_.size() != header_.header().size()) {
    return header_.Error(row_line_, "",
                         "row has " + std::to_string(fields_.size()) +
                             " fields but the header has " +
                             std::to_string(header_.header().size()));
  }
  return Status::Ok();
}

bool CsvReader::NextRecordStart() {
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

Status CsvReader::ParseRecord(bool header) {
  row_line_ = line_;
  fields_.clear();
  unescaped_.clear();
  unescaped_fields_.clear();
  while (true) {
    std::string_view field;
    PHOTOPOSE_RETURN_IF_ERROR(ParseField(header, fields_.size(), &field));
    fields_.push_back(field);
    if (pos_ < text_.size() && text_[pos_] == ',') {
      if (fields_.size() >= kMaxColumns) {
        return Status::Error(EscapeForMessage(*file_name_) + ":" + std::to_string(row_line_) +
                             ": the " + (header ? "header" : "row") + " has more than " +
                             std::to_string(kMaxColumns) + " fields; photopose reads at most " +
                             std::to_string(kMaxColumns) + " columns");
      }
      ++pos_;
      continue;
    }
    if (pos_ < text_.size()) {  // at '\n'
      ++pos_;
      ++line_;
    }
    // The unescaped fields point into unescaped_ only now that it no longer grows.
    for (const UnescapedField& u : unescaped_fields_)
      fields_[u.field] = std::string_view(unescaped_.data() + u.offset, u.size);
    return Status::Ok();
  }
}

std::string CsvReader::ColumnName(bool header, size_t index) const {
  if (!header && index < header_.header().size()) return TokenForMessage(header_.header()[index]);
  return "field " + std::to_string(index + 1);
}

Status CsvReader::ParseField(bool header, size_t index, std::string_view* field) {
  while (pos_ < text_.size() && IsBlank(text_[pos_])) ++pos_;
  if (pos_ < text_.size() && text_[pos_] == '"') {
    const int quote_line = line_;
    const size_t start = ++pos_;
    // A view of the text unless the field holds "" or a line break (unescaped into unescaped_).
    bool plain = true;
    size_t offset = unescaped_.size();
    const auto copy_so_far = [&](size_t end) {
      if (plain) unescaped_.append(text_.substr(start, end - start));
      plain = false;
    };
    while (true) {
      if (pos_ >= text_.size()) {
        return Status::Error(EscapeForMessage(*file_name_ + ":" + std::to_string(quote_line) +
                                              ": " + ColumnName(header, index) +
                                              ": quoted field is not closed"));
      }
      const char c = text_[pos_++];
      if (c == '"') {
        if (pos_ < text_.size() && text_[pos_] == '"') {
          copy_so_far(pos_ - 1);  // up to the first quote of the pair, which is the character
          unescaped_.push_back('"');
          ++pos_;
          continue;
        }
        if (plain) *field = text_.substr(start, pos_ - 1 - start);
        break;
      }
      if (c == '\n') {
        copy_so_far(pos_ - 1);
        ++line_;
        if (unescaped_.size() > offset && unescaped_.back() == '\r') unescaped_.pop_back();
      }
      if (!plain) unescaped_.push_back(c);
    }
    if (!plain) {
      unescaped_fields_.push_back({index, offset, unescaped_.size() - offset});
      *field = std::string_view();
    }
    while (pos_ < text_.size() && (IsBlank(text_[pos_]) || text_[pos_] == '\r')) ++pos_;
    if (pos_ < text_.size() && text_[pos_] != ',' && text_[pos_] != '\n') {
      return Status::Error(EscapeForMessage(*file_name_ + ":" + std::to_string(line_) + ": " +
                                            ColumnName(header, index) +
                                            ": text after the closing quote"));
    }
    return Status::Ok();
  }
  const size_t start = pos_;
  while (pos_ < text_.size() && text_[pos_] != ',' && text_[pos_] != '\n') ++pos_;
  *field = TrimBlanks(text_.substr(start, pos_ - start));
  return Status::Ok();
}

// ------------------------------------------------------------------ CsvTable

Status CsvTable::Read(const std::string& path, const CsvOptions& options, CsvTable* table) {
  std::string text;
  PHOTOPOSE_RETURN_IF_ERROR(ReadTextFile(path, &text));
  return Parse(text, InputName(path), options, table);
}

Status CsvTable::Parse(std::string_view text, const std::string& file_name,
                       const CsvOptions& options, CsvTable* table) {
  CsvReader reader;
  PHOTOPOSE_RETURN_IF_ERROR(reader.Open(text, file_name, options));
  CsvTable result;
  static_cast<CsvHeader&>(result) = reader.header();
  bool has_row = false;
  while (true) {
    PHOTOPOSE_RETURN_IF_ERROR(reader.Next(&has_row));
    if (!has_row) break;
    CsvRow row;
    row.line = reader.line();
    row.fields.assign(reader.fields().begin(), reader.fields().end());
    result.rows_.push_back(std::move(row));
  }
  *table = std::move(result);
  return Status::Ok();
}

// ------------------------------------------------------------------ CsvRowReader

CsvRowReader::CsvRowReader(const CsvTable& table, const CsvRow& row)
    : header_(table),
      line_(row.line),
      table_fields_(row.fields.begin(), row.fields.end()),
      fields_(&table_fields_) {}

Status CsvRowReader::RequiredText(const CsvColumn& column, std::string* value) const {
  const std::string_view text = Text(column);
  if (text.empty()) return Error(column, "is empty");
  value->assign(text.data(), text.size());
  return Status::Ok();
}

Status CsvRowReader::Number(const CsvColumn& column, std::optional<double>* value) const {
  const std::string_view text = Text(column);
  value->reset();
  if (text.empty()) return Status::Ok();
  double number = 0.0;
  std::string why;
  if (!ParseFiniteNumber(text, &number, &why)) return Error(column, why);
  *value = number;
  return Status::Ok();
}

Status CsvRowReader::RequiredNumber(const CsvColumn& column, double* value) const {
  std::optional<double> number;
  PHOTOPOSE_RETURN_IF_ERROR(Number(column, &number));
  if (!number) return Error(column, "is empty");
  *value = *number;
  return Status::Ok();
}

Status CsvRowReader::Integer(const CsvColumn& column, std::optional<long long>* value) const {
  const std::string_view text = Text(column);
  value->reset();
  if (text.empty()) return Status::Ok();
  long long number = 0;
  std::string why;
  if (!ParseWholeNumber(text, &number, &why)) return Error(column, why);
  *value = number;
  return Status::Ok();
}

Status CsvRowReader::NumberList(const CsvColumn& column, std::vector<double>* values) const {
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

Status CsvRowReader::NumberGroups(const CsvColumn& column, int group_size,
                                  std::vector<double>* values) const {
  values->clear();
  const std::string_view text = Text(column);
  if (text.empty()) return Status::Ok();
  const std::vector<std::string_view> groups = SplitOn(text, ';');
  for (size_t g = 0; g < groups.size(); ++g) {
    const std::string group_name = "item " + std::to_string(g + 1);
    const std::vector<std::string_view> words = SplitWords(TrimBlanks(groups[g]));
    if (words.size() != static_cast<size_t>(group_size)) {
      return Error(column, group_name + " " + QuotedToken(TrimBlanks(groups[g])) + " has " +
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

std::string InputName(const std::string& path) { return path == "-" ? "<stdin>" : path; }

Status ReadTextFile(const std::string& path, std::string* text) {
  const std::string name = EscapeForMessage(InputName(path));
  text->clear();
  const bool standard_input = path == "-";
  // O_NONBLOCK: opening a FIFO must not wait for a writer; it is refused below anyway.
  const int fd = standard_input ? STDIN_FILENO
                                : open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) return Status::Error(name + ": cannot open: " + std::strerror(errno));
  const auto finish = [&](Status status) {
    if (!standard_input) close(fd);
    if (!status.ok()) text->clear();
    return status;
  };
  struct stat info;
  if (fstat(fd, &info) != 0)
    return finish(Status::Error(name + ": cannot read: " + std::strerror(errno)));
  if (!standard_input && !S_ISREG(info.st_mode)) {
    return finish(Status::Error(name + ": is " + NodeKind(info.st_mode) +
                                ", not a regular file; photopose reads regular files, or standard "
                                "input for '-'"));
  }
  const std::string too_large = name + ": is larger than " + std::to_string(kMaxInputBytes) +
                                " bytes, the largest input photopose reads";
  if (S_ISREG(info.st_mode) && static_cast<uint64_t>(info.st_size) > kMaxInputBytes)
    return finish(Status::Error(too_large));
  // Read, not mapped: a file that shrinks while it is read gives a shorter text, where a mapping
  // would die of SIGBUS at the first page past the new end.
  const size_t expected = S_ISREG(info.st_mode) ? static_cast<size_t>(info.st_size) : 0;
  int error_number = 0;
  if (!ReadAtMost(fd, kMaxInputBytes, expected, text, &error_number))
    return finish(Status::Error(name + ": cannot read: " + std::strerror(error_number)));
  if (text->size() > kMaxInputBytes) return finish(Status::Error(too_large));
  return finish(Status::Ok());
}

Status CheckTextInput(std::string_view text, const std::string& file_name) {
  const std::string name = EscapeForMessage(file_name);
  using namespace std::string_view_literals;
  static constexpr std::pair<std::string_view, const char*> kByteOrderMarks[] = {
      {"\xFF\xFE\0\0"sv, "UTF-32 (little-endian byte order mark)"},
      {"\0\0\xFE\xFF"sv, "UTF-32 (big-endian byte order mark)"},
      {"\xFF\xFE"sv, "UTF-16 (little-endian byte order mark)"},
      {"\xFE\xFF"sv, "UTF-16 (big-endian byte order mark)"}};
  for (const auto& [mark, encoding] : kByteOrderMarks) {
    if (text.substr(0, mark.size()) == mark) {
      return Status::Error(name + ": is " + encoding +
                           "; photopose reads UTF-8 text: save the file as UTF-8");
    }
  }
  size_t i = text.substr(0, 3) == "\xEF\xBB\xBF" ? 3 : 0;
  int line = 1;
  size_t line_start = 0, character = 0;
  const auto error = [&](const std::string& what) {
    return Status::Error(name + ":" + std::to_string(line) + ": character " +
                         std::to_string(character) + ": " + what);
  };
  while (i < text.size()) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c == '\n') {
      ++line;
      line_start = ++i;
      character = 0;
      continue;
    }
    ++character;
    if (i - line_start >= kMaxLineBytes) {
      return Status::Error(name + ":" + std::to_string(line) + ": the line is longer than " +
                           std::to_string(kMaxLineBytes) +
                           " bytes, the longest line photopose reads");
    }
    if (c >= 0x20 && c < 0x7F) {  // printable ASCII, nearly every byte of a table
      ++i;
      continue;
    }
    if (c == 0) {
      return error(
          "NUL byte: photopose reads UTF-8 text (is this a binary file, or UTF-16 without a "
          "byte order mark?)");
    }
    if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7F)
      return error("control character " + HexByte(c) + ": photopose reads plain UTF-8 text");
    const size_t length = Utf8SequenceLength(text, i);
    if (length == 0)
      return error("byte " + HexByte(c) + " is not UTF-8; photopose reads UTF-8 text");
    i += length;
  }
  return Status::Ok();
}

namespace {

// Appends the character at text[i] to *escaped as EscapeForMessage writes it; returns the number
// of bytes it takes in `text`.
size_t AppendEscapedCharacter(std::string_view text, size_t i, std::string* escaped) {
  const unsigned char c = static_cast<unsigned char>(text[i]);
  if (c == '\t' || c == '\n' || c == '\r') {
    *escaped += c == '\t' ? "\\t" : c == '\n' ? "\\n" : "\\r";
    return 1;
  }
  const size_t length = c < 0x20 || c == 0x7F ? 0 : Utf8SequenceLength(text, i);
  if (length == 0) {
    *escaped += "\\x" + HexByte(c).substr(2);
    return 1;
  }
  escaped->append(text.substr(i, length));
  return length;
}

}  // namespace

std::string QuotedForMessage(std::string_view name) { return "'" + EscapeForMessage(name) + "'"; }

std::string WhereInFile(std::string_view file, int line, std::string_view column) {
  std::string where(file);
  if (line > 0) where += ":" + std::to_string(line);
  where += ": ";
  if (!column.empty()) where.append(column).append(": ");
  return where;
}

std::string EscapeForMessage(std::string_view text) {
  std::string escaped;
  escaped.reserve(text.size());
  for (size_t i = 0; i < text.size();) i += AppendEscapedCharacter(text, i, &escaped);
  return escaped;
}

std::string TokenForMessage(std::string_view token) {
  std::string escaped;
  size_t i = 0;
  for (size_t characters = 0; i < token.size() && characters < kMaxEchoedCharacters; ++characters)
    i += AppendEscapedCharacter(token, i, &escaped);
  if (i < token.size()) escaped += "\u2026(" + std::to_string(token.size()) + " bytes)";
  return escaped;
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
    *why = QuotedToken(text) + " is out of range";
    return false;
  }
  if (result.ec != std::errc() || result.ptr != end || digits.empty()) {
    *why = QuotedToken(text) + " is not a number";
    return false;
  }
  if (!std::isfinite(number)) {
    *why = QuotedToken(text) + " is not a finite number";
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
    *why = QuotedToken(text) + " is not a whole number";
    return false;
  }
  constexpr double kLimit = 9.2e18;  // inside the range of long long
  if (std::abs(real) > kLimit) {
    *why = QuotedToken(text) + " is out of range";
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

std::vector<std::string> SplitCommaList(const std::string& text) {
  std::vector<std::string> items;
  if (text.empty()) return items;
  for (const std::string_view part : SplitOn(text, ',')) items.emplace_back(TrimBlanks(part));
  // As a stream read item by item gives them: nothing after a final comma.
  if (!text.empty() && text.back() == ',') items.pop_back();
  return items;
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

void AppendFormattedNumber(double value, std::string* text) {
  // The shortest text that reads back exactly; positional (500000, 0.0125) rather than
  // scientific (5e+05) in the range of coordinates and accuracies, as a surveyor writes them.
  char buffer[400];
  const double magnitude = std::abs(value);
  const std::to_chars_result result =
      magnitude >= 1e-4 && magnitude < 1e15
          ? std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::fixed)
          : std::to_chars(buffer, buffer + sizeof(buffer), value);
  text->append(buffer, result.ptr);
}

std::string FormatNumber(double value) {
  std::string text;
  AppendFormattedNumber(value, &text);
  return text;
}

std::string FormatPlainNumber(double value) {
  if (value == std::floor(value) && std::abs(value) < 1e15) {
    char buffer[32];
    std::snprintf(buffer, sizeof(buffer), "%.0f", value);
    return buffer;
  }
  return FormatNumber(value);
}

std::string FormatNumberList(const std::vector<double>& values) {
  std::string text;
  for (size_t i = 0; i < values.size(); ++i) {
    if (i > 0) text += ';';
    text += FormatNumber(values[i]);
  }
  return text;
}

void AppendCsvField(std::string_view field, std::string* text) {
  const bool needs_quotes =
      field.find_first_of(",\"\n\r") != std::string_view::npos ||
      (!field.empty() && (IsBlank(field.front()) || IsBlank(field.back()) || field.front() == '#'));
  if (!needs_quotes) {
    text->append(field);
    return;
  }
  *text += '"';
  for (const char c : field) {
    if (c == '"') *text += '"';
    *text += c;
  }
  *text += '"';
}

std::string CsvQuote(std::string_view field) {
  std::string quoted;
  AppendCsvField(field, &quoted);
  return quoted;
}

std::string CsvLine(const std::vector<std::string>& fields) {
  // A single empty field would make an empty line, which readers skip.
  if (fields.size() == 1 && fields[0].empty()) return "\"\"\n";
  std::string line;
  for (size_t i = 0; i < fields.size(); ++i) {
    if (i > 0) line += ',';
    AppendCsvField(fields[i], &line);
  }
  line += '\n';
  return line;
}

}  // namespace photopose
