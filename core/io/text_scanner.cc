#include "core/io/text_scanner.h"

#include <charconv>
#include <cmath>

#include "core/io/csv.h"

namespace photopose {

bool TextLines::Next(std::string_view* line, int* line_number) {
  if (position_ >= text_.size()) return false;
  size_t end = text_.find('\n', position_);
  if (end == std::string_view::npos) end = text_.size();
  size_t stop = end;
  if (stop > position_ && text_[stop - 1] == '\r') --stop;
  *line = text_.substr(position_, stop - position_);
  *line_number = ++line_number_;
  position_ = end + 1;
  return true;
}

int TokenScanner::line() {
  SkipBlanks();
  return line_;
}

bool TokenScanner::AtEnd() {
  SkipBlanks();
  return position_ >= text_.size();
}

std::string_view TokenScanner::Rest() {
  SkipBlanks();
  std::string_view rest = text_.substr(position_);
  while (!rest.empty() && IsSeparator(rest.back())) rest.remove_suffix(1);
  return rest;
}

Status TokenScanner::Number(std::string_view field, double* value) {
  std::string_view word;
  PHOTOPOSE_RETURN_IF_ERROR(Word(field, &word));
  std::string why;
  if (!ParseFiniteNumber(word, value, &why)) return Error(field, why);
  return Status::Ok();
}

Status TokenScanner::Integer(std::string_view field, long long* value) {
  std::string_view word;
  PHOTOPOSE_RETURN_IF_ERROR(Word(field, &word));
  std::string why;
  if (!ParseWholeNumber(word, value, &why)) return Error(field, why);
  return Status::Ok();
}

Status TokenScanner::IntegerIn(std::string_view field, long long min, long long max,
                               long long* value) {
  PHOTOPOSE_RETURN_IF_ERROR(Integer(field, value));
  if (*value < min || *value > max) {
    return Error(field, std::to_string(*value) + " is out of range [" + std::to_string(min) +
                            ", " + std::to_string(max) + "]");
  }
  return Status::Ok();
}

Status TokenScanner::NumberWithin(std::string_view field, double max_magnitude,
                                  std::string_view unit, double* value) {
  std::string_view word;
  PHOTOPOSE_RETURN_IF_ERROR(Word(field, &word));
  std::string why;
  if (!ParseFiniteNumber(word, value, &why)) return Error(field, why);
  if (!(std::abs(*value) <= max_magnitude)) {
    return Error(field, "'" + TokenForMessage(word) + "' is outside [" +
                            FormatPlainNumber(-max_magnitude) + ", " +
                            FormatPlainNumber(max_magnitude) + "]" + (unit.empty() ? "" : " ") +
                            std::string(unit));
  }
  return Status::Ok();
}

Status TokenScanner::Error(std::string_view field, std::string_view what) {
  return TextError(file_, line_, field, what);
}

Status TextError(const std::string& file, int line, std::string_view field, std::string_view what) {
  std::string message = file;
  if (line > 0) message += ":" + std::to_string(line);
  message += ": ";
  if (!field.empty()) {
    message += field;
    message += ": ";
  }
  message += what;
  return Status::Error(EscapeForMessage(message));
}

bool IsBlankOrComment(std::string_view line) {
  size_t i = 0;
  while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
  return i == line.size() || line[i] == '#';
}

void AppendNumber(double value, std::string* text) {
  char buffer[32];
  const std::to_chars_result result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  text->append(buffer, result.ptr);
}

void AppendInteger(long long value, std::string* text) {
  char buffer[24];
  const std::to_chars_result result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  text->append(buffer, result.ptr);
}

}  // namespace photopose
