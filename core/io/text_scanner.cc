#include "core/io/text_scanner.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>

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
  return Status::Error(std::move(message));
}

TextFile::~TextFile() { Close(); }

void TextFile::Close() {
  if (map_ != nullptr) munmap(map_, map_size_);
  map_ = nullptr;
  map_size_ = 0;
  read_.clear();
  text_ = std::string_view();
}

bool TextFile::Map(int fd, size_t size) {
  void* map = mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
  if (map == MAP_FAILED) return false;
  madvise(map, size, MADV_SEQUENTIAL);
  map_ = map;
  map_size_ = size;
  text_ = std::string_view(static_cast<const char*>(map_), map_size_);
  return true;
}

Status TextFile::Open(const std::string& path) { return OpenFile(path, /*as_input=*/false); }

Status TextFile::OpenInput(const std::string& path) { return OpenFile(path, /*as_input=*/true); }

Status TextFile::OpenFile(const std::string& path, bool as_input) {
  Close();
  // As an input, O_NONBLOCK: opening a FIFO must not wait for a writer (ReadTextFile refuses it).
  const int flags = O_RDONLY | O_CLOEXEC | (as_input ? O_NONBLOCK | O_NOCTTY : 0);
  const int fd = as_input && path == "-" ? -1 : open(path.c_str(), flags);
  if (fd < 0 && !as_input) return Status::Error(path + ": cannot open: " + std::strerror(errno));
  if (fd >= 0) {
    struct stat info;
    const bool mapped =
        fstat(fd, &info) == 0 && S_ISREG(info.st_mode) && info.st_size > 0 &&
        (!as_input || static_cast<uint64_t>(info.st_size) <= kMaxInputBytes) &&
        Map(fd, static_cast<size_t>(info.st_size));
    close(fd);
    if (mapped) return Status::Ok();
  }
  // Standard input, not a regular file, empty, too large or not mappable: read it, or refuse it,
  // with ReadTextFile's messages.
  PHOTOPOSE_RETURN_IF_ERROR(ReadTextFile(path, &read_));
  text_ = read_;
  return Status::Ok();
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
