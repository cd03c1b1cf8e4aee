// The ground points and image marks tables, their consistency, marks inside their image (core/io/tables.h).
#include "core/io/tables.h"


#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstring>
#include <deque>
#include <functional>
#include <map>
#include <string_view>

#include "core/io/csv.h"
#include "core/io/text_scanner.h"
#include "core/io/internal/table_fields.h"

namespace photopose {
using namespace table_io;  // NOLINT: the shared table machinery of this folder
namespace {

// ------------------------------------------------------------------ ground points and marks

// A point's AccuracyX/Y/Z (m): unlike a frame's, 0 is a value (all three 0: held fixed, the rule
// of core/block.h, InvalidPointAccuracyAxis).
constexpr ValueRange kPointAccuracyRange{0.0, kMaxCoordinate, false, false, "m"};

// The points table's columns, looked up once per table.
struct PointTableColumns {
  explicit PointTableColumns(const CsvHeader& header)
      : point_id(LookUp(header, "PointID")),
        x(LookUp(header, "X")),
        y(LookUp(header, "Y")),
        z(LookUp(header, "Z")),
        accuracy{{header.Column(kAccuracyColumns[0]), &kPointAccuracyRange},
                 {header.Column(kAccuracyColumns[1]), &kPointAccuracyRange},
                 {header.Column(kAccuracyColumns[2]), &kPointAccuracyRange}},
        role(LookUp(header, "Role")) {}
  TableColumn point_id, x, y, z, accuracy[3], role;
};

// What breaks the accuracy rule of core/block.h on `axis` (InvalidPointAccuracyAxis), for messages.
std::string MixedAccuracyProblem(const Eigen::Vector3d& accuracy, int axis) {
  const int other = axis == 0 ? 1 : 0;
  return FormatPlainNumber(accuracy[axis]) + " beside " + std::string(kAccuracyColumns[other]) +
         " " + FormatPlainNumber(accuracy[other]) +
         ": AccuracyX, AccuracyY, AccuracyZ are all positive, or all 0 (the point held fixed)";
}

Status ReadPointRow(const CsvRowReader& row, const PointTableColumns& c, GroundPoint* point) {
  GroundPoint p;
  p.line = row.line();
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText(c.point_id.csv, &p.point_id));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, c.x, &p.position[0]));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, c.y, &p.position[1]));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, c.z, &p.position[2]));
  if (row.Has(c.accuracy[0].csv) || row.Has(c.accuracy[1].csv) || row.Has(c.accuracy[2].csv)) {
    Eigen::Vector3d accuracy;
    for (int i = 0; i < 3; ++i) {
      std::optional<double> sigma;
      PHOTOPOSE_RETURN_IF_ERROR(ReadNumber(row, c.accuracy[i], &sigma));
      if (!sigma) {
        return row.Error(c.accuracy[i].csv,
                         "is empty; AccuracyX, AccuracyY, AccuracyZ are given together");
      }
      accuracy[i] = *sigma;
    }
    const int axis = InvalidPointAccuracyAxis(accuracy);
    if (axis >= 0) return row.Error(c.accuracy[axis].csv, MixedAccuracyProblem(accuracy, axis));
    p.accuracy_m = accuracy;
  }
  PHOTOPOSE_RETURN_IF_ERROR(ReadEnum(row, c.role.csv, EnumNames(PointRole{}), &p.role));
  *point = std::move(p);
  return Status::Ok();
}

// The marks table's columns, looked up once per table.
struct MarkTableColumns {
  explicit MarkTableColumns(const CsvHeader& header)
      : raster(LookUp(header, "Raster")),
        point_id(LookUp(header, "PointID")),
        column(LookUp(header, "Column")),
        row(LookUp(header, "Row")),
        film_x(LookUp(header, "FilmX")),
        film_y(LookUp(header, "FilmY")),
        accuracy(LookUp(header, "Accuracy")),
        camera_id(LookUp(header, "CameraID")) {}
  TableColumn raster, point_id, column, row, film_x, film_y, accuracy, camera_id;
};

// Column/Row (pixels) or FilmX/FilmY (um): exactly one pair.
Status ReadMarkPosition(const CsvRowReader& row, const MarkTableColumns& c, ImageMark* mark) {
  const bool pixels = row.Has(c.column.csv) || row.Has(c.row.csv);
  const bool film = row.Has(c.film_x.csv) || row.Has(c.film_y.csv);
  if (pixels && film)
    return row.Error(c.film_x.csv, "give either Column/Row or FilmX/FilmY, not both");
  if (!pixels && !film) {
    return row.Error(c.column.csv,
                     "is empty; give Column and Row (pixels) or FilmX and FilmY (um)");
  }
  Eigen::Vector2d xy;
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, pixels ? c.column : c.film_x, &xy[0]));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, pixels ? c.row : c.film_y, &xy[1]));
  if (pixels) {
    mark->column_row = xy;
  } else {
    mark->film_um = xy;
  }
  return Status::Ok();
}

// Reads a row into *mark, whose strings keep their buffers from the row before.
Status ReadMarkRow(const CsvRowReader& row, const MarkTableColumns& c, ImageMark* mark) {
  mark->line = row.line();
  mark->column_row.reset();
  mark->film_um.reset();
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText(c.raster.csv, &mark->raster));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText(c.point_id.csv, &mark->point_id));
  PHOTOPOSE_RETURN_IF_ERROR(ReadMarkPosition(row, c, mark));
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumber(row, c.accuracy, &mark->accuracy_px));
  const std::string_view camera_id = row.Text(c.camera_id.csv);
  mark->camera_id.assign(camera_id.data(), camera_id.size());
  return Status::Ok();
}

std::string MarkDescription(std::string_view raster, std::string_view point_id) {
  return "mark of point " + QuotedForMessage(point_id) + " in image " + QuotedForMessage(raster);
}

// Duplicate marks (a point marked twice in one image), found without a string, an allocation or
// a random look-up per mark: each mark is kept as the dense ids of its raster and point (8 bytes),
// and the check sorts the marks by point (counting sort, stable) and compares each point's rasters
// through a stamp per raster, in time linear in the marks however they are spread.
class DuplicateMarks {
 public:
  // `stable_text`: see NameIds.
  DuplicateMarks(std::string_view stable_text, size_t expected_marks)
      : rasters_(stable_text), points_(stable_text) {
    pairs_.reserve(expected_marks);
  }

  // Adds the next mark (numbered from 0).
  void Add(std::string_view raster, std::string_view point_id) {
    bool is_new = false;
    const int raster_id = rasters_.Id(raster, &is_new);
    pairs_.push_back({raster_id, points_.Id(point_id, &is_new)});
  }
  std::string_view Raster(size_t mark) const { return rasters_.Name(pairs_[mark].raster); }
  std::string_view PointId(size_t mark) const { return points_.Name(pairs_[mark].point); }

  // The first mark (in the order added) whose point and raster an earlier mark has, and that
  // earlier mark (the first of the pair); false when there is none.
  bool FindFirst(size_t* duplicate, size_t* first) const {
    std::vector<size_t> start(points_.size() + 1, 0);
    for (const Pair& pair : pairs_) ++start[pair.point + 1];
    for (size_t p = 0; p < points_.size(); ++p) start[p + 1] += start[p];
    std::vector<uint32_t> by_point(pairs_.size());
    {
      std::vector<size_t> next(start.begin(), start.end() - 1);
      for (size_t m = 0; m < pairs_.size(); ++m)
        by_point[next[pairs_[m].point]++] = static_cast<uint32_t>(m);
    }
    // The last point seen in each raster and its first mark there.
    std::vector<int> point_in_raster(rasters_.size(), -1);
    std::vector<uint32_t> first_in_raster(rasters_.size(), 0);
    bool found = false;
    for (size_t p = 0; p < points_.size(); ++p) {
      for (size_t i = start[p]; i < start[p + 1]; ++i) {
        const uint32_t m = by_point[i];
        const int raster = pairs_[m].raster;
        if (point_in_raster[raster] != static_cast<int>(p)) {
          point_in_raster[raster] = static_cast<int>(p);
          first_in_raster[raster] = m;
        } else if (!found || m < *duplicate) {
          found = true;
          *duplicate = m;
          *first = first_in_raster[raster];
        }
      }
    }
    return found;
  }

 private:
  struct Pair {
    int raster;
    int point;
  };
  NameIds rasters_, points_;
  std::vector<Pair> pairs_;
};


}  // namespace

// ------------------------------------------------------------------ ground points

Status ParseGroundPoints(std::string_view text, const std::string& file_name,
                         std::vector<GroundPoint>* points) {
  CsvReader reader;
  PHOTOPOSE_RETURN_IF_ERROR(reader.Open(text, file_name, kTableCsvOptions));
  const CsvHeader& table = reader.header();
  PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns({"PointID", "X", "Y", "Z"}));
  if (table.HasColumn("AccuracyX") || table.HasColumn("AccuracyY") || table.HasColumn("AccuracyZ"))
    PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns({"AccuracyX", "AccuracyY", "AccuracyZ"}));

  const PointTableColumns columns(table);
  std::vector<GroundPoint> result;
  result.reserve(reader.MaxRows());
  FirstLines first_lines(text);
  PHOTOPOSE_RETURN_IF_ERROR(reader.ForEachRow([&](const CsvRowReader& row) {
    GroundPoint& point = result.emplace_back();
    PHOTOPOSE_RETURN_IF_ERROR(ReadPointRow(row, columns, &point));
    return CheckUnique(row, "PointID", row.Text(columns.point_id.csv), "point", &first_lines);
  }));
  *points = std::move(result);
  return Status::Ok();
}

Status FormatGroundPoints(const std::vector<GroundPoint>& points, const std::string& path,
                          std::string* text) {
  std::string contents = CsvLine(HeaderFields(PointColumns()));
  for (const GroundPoint& p : points) {
    RowFields row("point " + QuotedForMessage(p.point_id));
    if (p.point_id.empty()) row.Fail("PointID", "is empty");
    row.Text(p.point_id);
    row.Number("X", p.position.x());
    row.Number("Y", p.position.y());
    row.Number("Z", p.position.z());
    const int axis = p.accuracy_m ? InvalidPointAccuracyAxis(*p.accuracy_m) : -1;
    if (axis >= 0) row.Fail(kAccuracyColumns[axis], MixedAccuracyProblem(*p.accuracy_m, axis));
    for (int i = 0; i < 3; ++i) {
      row.OptionalNumber(kAccuracyColumns[i],
                         p.accuracy_m ? std::optional<double>((*p.accuracy_m)[i]) : std::nullopt,
                         &kPointAccuracyRange);
    }
    row.Text(EnumName(p.role));
    PHOTOPOSE_RETURN_IF_ERROR(row.status(path));
    contents += CsvLine(*row.fields());
  }
  *text = std::move(contents);
  return Status::Ok();
}

// ------------------------------------------------------------------ image marks

Status ParseImageMarks(std::string_view text, const std::string& file_name,
                       std::vector<ImageMark>* marks) {
  CsvReader reader;
  PHOTOPOSE_RETURN_IF_ERROR(reader.Open(text, file_name, kTableCsvOptions));
  const CsvHeader& table = reader.header();
  PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns({"Raster", "PointID"}));
  PHOTOPOSE_RETURN_IF_ERROR(RequirePairedColumns(table, "Column", "Row"));
  PHOTOPOSE_RETURN_IF_ERROR(RequirePairedColumns(table, "FilmX", "FilmY"));
  if (!table.HasColumn("Column") && !table.HasColumn("FilmX")) {
    return table.Error(table.header_line(), "Column",
                       "required column is missing (give Column and Row, or FilmX and FilmY)");
  }

  const MarkTableColumns columns(table);
  const size_t max_rows = reader.MaxRows();
  std::vector<ImageMark> result;
  result.reserve(max_rows);
  DuplicateMarks duplicates(text, max_rows);
  const Status read = reader.ForEachRow([&](const CsvRowReader& row) {
    ImageMark& mark = result.emplace_back();
    PHOTOPOSE_RETURN_IF_ERROR(ReadMarkRow(row, columns, &mark));
    // The names as views of the text (the mark's strings are copies).
    duplicates.Add(row.Text(columns.raster.csv), row.Text(columns.point_id.csv));
    return Status::Ok();
  });
  // The first problem in the file: a duplicate among the rows before a bad one comes first.
  size_t duplicate = 0, first = 0;
  if (duplicates.FindFirst(&duplicate, &first)) {
    return table.Error(result[duplicate].line, "PointID",
                       "duplicate " +
                           MarkDescription(duplicates.Raster(duplicate),
                                           duplicates.PointId(duplicate)) +
                           " (first on line " + std::to_string(result[first].line) + ")");
  }
  PHOTOPOSE_RETURN_IF_ERROR(read);
  *marks = std::move(result);
  return Status::Ok();
}

struct ImageMarksWriter::State {
  State(const std::string& path, size_t num_marks)
      : path(path),
        duplicates(std::string_view(), num_marks),
        column(RangeOf("Column")),
        row(RangeOf("Row")),
        film_x(RangeOf("FilmX")),
        film_y(RangeOf("FilmY")),
        accuracy(RangeOf("Accuracy")) {
    lines.reserve(num_marks);
  }
  // The reader rejects a second mark of a point in an image: "path: mark of point 'P' in image
  // 'I': PointID: the point is marked twice in the image (source lines 3 and 9)" for the first
  // such mark up to `last` (all when npos), if any.
  Status CheckDuplicates(size_t last) const {
    size_t duplicate = 0, first = 0;
    if (!duplicates.FindFirst(&duplicate, &first) || duplicate > last) return Status::Ok();
    return Status::Error(EscapeForMessage(
        path + ": " + MarkDescription(duplicates.Raster(duplicate), duplicates.PointId(duplicate)) +
        ": PointID: the point is marked twice in the image (source lines " +
        std::to_string(lines[first]) + " and " + std::to_string(lines[duplicate]) + ")"));
  }

  const std::string path;
  DuplicateMarks duplicates;
  std::vector<int> lines;  // source line of every mark added
  const ValueRange *column, *row, *film_x, *film_y, *accuracy;
};

ImageMarksWriter::ImageMarksWriter(const std::string& path, size_t num_marks, std::string* text)
    : state_(std::make_unique<State>(path, num_marks)), text_(text) {
  // About 70 bytes per row for names of a dozen characters: one allocation, mostly.
  text_->reserve(text_->size() + 128 + 80 * num_marks);
  *text_ += CsvLine(HeaderFields(MarkColumns()));
}

ImageMarksWriter::~ImageMarksWriter() = default;

Status ImageMarksWriter::Add(const ImageMark& m) {
  const size_t number = state_->lines.size();
  state_->duplicates.Add(m.raster, m.point_id);
  state_->lines.push_back(m.line);
  // The first problem in the order of the columns, as RowFields keeps it (a duplicate, checked at
  // the end or at the first other problem, comes first); no string is made for a good row.
  std::string problem;
  const auto fail = [&problem](std::string_view column, const std::string& what) {
    if (problem.empty()) problem = std::string(column) + ": " + what;
  };
  if (m.raster.empty()) fail("Raster", "is empty");
  if (m.point_id.empty()) fail("PointID", "is empty");
  if (m.column_row.has_value() == m.film_um.has_value())
    fail("Column", "exactly one of Column/Row and FilmX/FilmY must be set");
  if (m.accuracy_px && !(*m.accuracy_px > 0.0)) fail("Accuracy", "must be positive");
  const auto check = [&fail](std::string_view column, const ValueRange* range, double value) {
    if (std::isfinite(value) && InRange(value, *range)) return;
    fail(column, ValueProblem(value, range));
  };
  if (m.column_row) {
    check("Column", state_->column, m.column_row->x());
    check("Row", state_->row, m.column_row->y());
  }
  if (m.film_um) {
    check("FilmX", state_->film_x, m.film_um->x());
    check("FilmY", state_->film_y, m.film_um->y());
  }
  if (m.accuracy_px) check("Accuracy", state_->accuracy, *m.accuracy_px);
  if (!problem.empty()) {
    PHOTOPOSE_RETURN_IF_ERROR(state_->CheckDuplicates(number));
    return Status::Error(EscapeForMessage(state_->path + ": " +
                                          MarkDescription(m.raster, m.point_id) + ": " + problem));
  }

  std::string& text = *text_;
  AppendCsvField(m.raster, &text);
  text += ',';
  AppendCsvField(m.point_id, &text);
  const auto number_field = [&text](const std::optional<double>& value) {
    text += ',';
    if (value) AppendFormattedNumber(*value, &text);
  };
  number_field(m.column_row ? std::optional<double>(m.column_row->x()) : std::nullopt);
  number_field(m.column_row ? std::optional<double>(m.column_row->y()) : std::nullopt);
  number_field(m.film_um ? std::optional<double>(m.film_um->x()) : std::nullopt);
  number_field(m.film_um ? std::optional<double>(m.film_um->y()) : std::nullopt);
  number_field(m.accuracy_px);
  text += ',';
  AppendCsvField(m.camera_id, &text);
  text += '\n';
  return Status::Ok();
}

Status ImageMarksWriter::Finish() { return state_->CheckDuplicates(std::string::npos); }

Status FormatImageMarks(const std::vector<ImageMark>& marks, const std::string& path,
                        std::string* text) {
  std::string contents;
  ImageMarksWriter writer(path, marks.size(), &contents);
  for (const ImageMark& m : marks) PHOTOPOSE_RETURN_IF_ERROR(writer.Add(m));
  PHOTOPOSE_RETURN_IF_ERROR(writer.Finish());
  *text = std::move(contents);
  return Status::Ok();
}


// ------------------------------------------------------------------ consistency

Status CheckMarks(const std::string& marks_path, const std::vector<ImageMark>& marks,
                  const std::vector<GroundPoint>& points) {
  std::map<std::string, int> known;
  for (const GroundPoint& p : points) known.emplace(p.point_id, p.line);
  for (const ImageMark& m : marks) {
    if (known.count(m.point_id) == 0)
      return Status::Error(WhereInFile(marks_path, m.line) + "PointID: unknown point " +
                           QuotedForMessage(m.point_id));
  }
  return Status::Ok();
}

// ------------------------------------------------------------------ marks inside their image

Status CheckMarkInsideImage(const std::string& marks_path, const ImageMark& mark,
                            const FrameCamera& camera, PixelOrigin origin) {
  if (camera.n_columns <= 0 || camera.n_rows <= 0) return Status::Ok();
  Eigen::Vector2d column_row;
  if (mark.column_row) {
    column_row = *mark.column_row;
  } else if (!mark.film_um || !PixelFromFilm(camera, *mark.film_um, origin, &column_row).ok()) {
    return Status::Ok();  // no way to pixels: other checks say why
  }
  const Eigen::Vector2d size(camera.n_columns, camera.n_rows);
  const Eigen::Vector2d margin = kMarkOutsideImageFraction * size;
  const double shift = origin == PixelOrigin::kCenter ? 0.5 : 0.0;  // corner-based from here on
  for (int k = 0; k < 2; ++k) {
    const double value = column_row[k] + shift;
    const double outside = value < 0.0 ? -value : value - size[k];
    if (!(outside <= margin[k])) {
      const char* column =
          mark.column_row ? (k == 0 ? "Column" : "Row") : (k == 0 ? "FilmX" : "FilmY");
      return Status::Error(EscapeForMessage(
          WhereInFile(marks_path, mark.line) + column + ": the mark of point '" + mark.point_id +
          "' in image '" + mark.raster + "' lies " + FormatNumber(std::round(outside)) +
          " pixels outside the " + std::to_string(camera.n_columns) + " x " +
          std::to_string(camera.n_rows) + " image of camera '" + camera.camera_id + "' (at most " +
          FormatNumber(kMarkOutsideImageFraction * 100.0) + "% of the image size is allowed)"));
    }
  }
  return Status::Ok();
}


}  // namespace photopose
