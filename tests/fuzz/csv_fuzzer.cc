// libFuzzer harness: the CSV layer (core/io/csv.h) on arbitrary bytes. Every field of every row is
// read through every typed accessor; a message must be one clean line.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/io/csv.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  using photopose::CsvRowReader;
  using photopose::CsvTable;
  // The first byte picks the header matching; the rest is the file.
  const photopose::CsvOptions options{/*tolerant_header=*/(data[0] & 1) != 0};
  const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);
  CsvTable table;
  const photopose::Status status = CsvTable::Parse(text, "fuzz.csv", options, &table);
  photopose::fuzz::CheckMessage(status);
  if (!status.ok()) return 0;
  for (const auto& row : table.rows()) {
    if (row.fields.size() != table.header().size()) std::abort();
    const CsvRowReader reader(table, row);
    for (const std::string& column : table.header()) {
      std::optional<double> number;
      photopose::fuzz::CheckMessage(reader.Number(column, &number));
      if (number && !std::isfinite(*number)) std::abort();
      std::optional<long long> whole;
      photopose::fuzz::CheckMessage(reader.Integer(column, &whole));
      std::vector<double> list;
      photopose::fuzz::CheckMessage(reader.NumberList(column, &list));
      photopose::fuzz::CheckMessage(reader.NumberGroups(column, 2, &list));
    }
  }
  return 0;
}
