#include "core/io/fiducials_table.h"

#include <map>
#include <optional>
#include <utility>

#include "core/io/csv.h"

namespace photopose {

Status ReadMeasuredFiducials(const std::string& path, std::vector<MeasuredFiducial>* fiducials) {
  CsvTable table;
  PHOTOPOSE_RETURN_IF_ERROR(CsvTable::Read(path, CsvOptions{/*tolerant_header=*/true}, &table));
  PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns({"Raster", "FiducialID", "Column", "Row"}));
  std::vector<MeasuredFiducial> result;
  std::map<std::pair<std::string, int>, int> first_lines;
  for (const CsvRow& csv_row : table.rows()) {
    const CsvRowReader row(table, csv_row);
    MeasuredFiducial f;
    f.line = csv_row.line;
    PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText("Raster", &f.raster));
    std::optional<long long> id;
    PHOTOPOSE_RETURN_IF_ERROR(row.Integer("FiducialID", &id));
    if (!id || *id < 1 || *id > 1000)
      return row.Error("FiducialID", "must be the 1-based number of a FilmFiducials entry");
    f.fiducial_id = static_cast<int>(*id);
    PHOTOPOSE_RETURN_IF_ERROR(row.RequiredNumber("Column", &f.column_row[0]));
    PHOTOPOSE_RETURN_IF_ERROR(row.RequiredNumber("Row", &f.column_row[1]));
    const auto [it, inserted] = first_lines.emplace(std::make_pair(f.raster, f.fiducial_id), f.line);
    if (!inserted) {
      return row.Error("FiducialID", "fiducial " + std::to_string(f.fiducial_id) + " of image '" +
                                         f.raster + "' is measured twice (first on line " +
                                         std::to_string(it->second) + ")");
    }
    result.push_back(std::move(f));
  }
  *fiducials = std::move(result);
  return Status::Ok();
}

}  // namespace photopose
