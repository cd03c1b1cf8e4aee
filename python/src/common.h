#pragma once
// What every translation unit of the Python module shares: the enum <-> str conversion over the
// library's one name table per enum (core/enum_names.h), a failed Status as photopose.Error, the
// numpy conversions with their shape and dtype checks, keyword constructors and readable reprs of
// the option structs, paths as str or os.PathLike.
//
// Arrays: float64, C order; rows are items (N x 2 marks, N x 3 points, N x 6 poses). Inputs are
// converted (copied only when the dtype or layout differs, then into the C++ vectors the library
// takes); outputs are new arrays owned by Python.

#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <Eigen/Core>
#include <algorithm>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/camera.h"
#include "core/camera_models.h"
#include "core/enum_names.h"
#include "core/io/colmap.h"
#include "core/pixel_rows.h"
#include "core/rotation.h"
#include "core/status.h"
#include "core/termination.h"
#include "cost_functions/collinearity_cost.h"
#include "cost_functions/losses.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/resection/absolute_pose.h"
#include "solvers/resection/pose_refinement.h"
#include "solvers/resection/resection.h"
#include "solvers/resection/taylor_resection.h"

namespace photopose::python {

namespace py = pybind11;

// A failed Status, raised in Python as photopose.Error (a ValueError) with the Status' message.
class StatusError : public std::runtime_error {
 public:
  explicit StatusError(const std::string& message) : std::runtime_error(message) {}
};

inline void ThrowIfError(const Status& status) {
  if (!status.ok()) throw StatusError(status.message());
}

// Raises photopose.Error with "why" when an options struct's IsValid(std::string*) fails.
template <typename Options>
void CheckOptions(const Options& options, const char* name) {
  std::string why;
  if (!options.IsValid(&why)) throw StatusError(std::string(name) + ": " + why);
}

// A path argument: str or os.PathLike (os.fspath).
std::string PathArgument(const py::handle& path, const char* name);
// An optional path argument: empty for None (the file left out).
inline std::string OptionalPathArgument(const py::handle& path, const char* name) {
  return path.is_none() ? std::string() : PathArgument(path, name);
}

// ------------------------------------------------------------------ numpy in

// `value` as a float64 array of shape (N, columns) (a 1-D array of `columns` values is one row;
// an empty sequence is N = 0). Raises ValueError naming `name`, the expected and the given shape
// or dtype; None is refused unless `allow_none` (then an empty optional).
py::array_t<double, py::array::c_style> Matrix(const py::handle& value, const char* name,
                                               int columns);
// A float64 vector of length n (n < 0: any length). A scalar is broadcast when `broadcast`.
std::vector<double> Vector(const py::handle& value, const char* name, long n, bool broadcast);
std::vector<Eigen::Vector2d> Points2(const py::handle& value, const char* name);
std::vector<Eigen::Vector3d> Points3(const py::handle& value, const char* name);
Eigen::Vector3d Vector3(const py::handle& value, const char* name);
Eigen::Matrix3d Matrix3(const py::handle& value, const char* name);
// A list of str (or None: empty).
std::vector<std::string> Strings(const py::handle& value, const char* name);

// ------------------------------------------------------------------ numpy out

py::array_t<double> ToArray(const std::vector<Eigen::Vector2d>& rows);
py::array_t<double> ToArray(const std::vector<Eigen::Vector3d>& rows);
// A column of numbers as a numpy array of the same element type (float64, float32, int32).
template <typename T>
py::array_t<T> ToArray(const std::vector<T>& values) {
  py::array_t<T> out(static_cast<py::ssize_t>(values.size()));
  std::copy(values.begin(), values.end(), out.mutable_data());
  return out;
}
py::array_t<bool> ToBoolArray(const std::vector<char>& flags);
inline double NaN() { return std::numeric_limits<double>::quiet_NaN(); }
// One field of every row, in order: Column(block.marks, &BlockMark::image).
template <typename Row, typename Field>
std::vector<Field> Column(const std::vector<Row>& rows, Field Row::*field) {
  std::vector<Field> column;
  column.reserve(rows.size());
  for (const Row& row : rows) column.push_back(row.*field);
  return column;
}
// N x columns: get(i) is an optional vector (or a pointer-like), a row of NaN where it is empty.
template <typename Get>
py::array_t<double> OptionalRowsArray(size_t n, int columns, Get get) {
  py::array_t<double> out({static_cast<py::ssize_t>(n), py::ssize_t(columns)});
  double* d = out.mutable_data();
  for (size_t i = 0; i < n; ++i) {
    const auto value = get(i);
    for (int k = 0; k < columns; ++k) d[columns * i + k] = value ? (*value)[k] : NaN();
  }
  return out;
}
// N x rows x cols: get(i) is an optional matrix (or a pointer-like), NaN where it is empty.
template <typename Get>
py::array_t<double> StackOrNaN(size_t n, int rows, int cols, Get get) {
  py::array_t<double> out({static_cast<py::ssize_t>(n), py::ssize_t(rows), py::ssize_t(cols)});
  auto view = out.mutable_unchecked<3>();
  for (size_t i = 0; i < n; ++i) {
    const auto m = get(i);
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) view(i, r, c) = m ? (*m)(r, c) : NaN();
  }
  return out;
}

// [R | -R X0; 0 0 0 1] of a pose (R = R_camera_from_ground): ground (m) -> camera (u, v, w) (m).
Eigen::Matrix4d PoseMatrix(const ExteriorOrientation& eo);

// ------------------------------------------------------------------ option structs

// "TypeName(field=value, ...)" over the class's properties in declaration order.
std::string PropertiesRepr(const py::handle& self);
// Sets each keyword argument as an attribute of `self`; an unknown name is a TypeError listing the
// known ones, a wrong value the attribute's own error.
void SetKeywordAttributes(const py::handle& self, const py::kwargs& kwargs);

// Binds T with a keyword constructor (every field a keyword, defaults the C++ ones) and a repr.
template <typename T>
py::class_<T> BindStruct(py::handle scope, const char* name, const char* doc) {
  py::class_<T> cls(scope, name, doc);
  cls.def(py::init([](const py::kwargs& kwargs) {
            py::object self = py::cast(T());
            SetKeywordAttributes(self, kwargs);
            return self.cast<T>();
          }),
          "Every field as a keyword argument; unset fields keep the C++ defaults.");
  cls.def("__repr__", [](const py::object& self) { return PropertiesRepr(self); });
  cls.def("__copy__", [](const T& self) { return T(self); });
  cls.def("__deepcopy__", [](const T& self, const py::dict&) { return T(self); });
  return cls;
}

// Binds IsValid(std::string*) as validate(), raising photopose.Error with the reason.
template <typename T>
void DefValidate(py::class_<T>& cls, const char* name) {
  cls.def(
      "validate", [name](const T& self) { CheckOptions(self, name); },
      "Raises photopose.Error naming the first field out of range.");
}

// ------------------------------------------------------------------ the block
// photopose.Block: a Block (core/block.h) and, when it was read from a COLMAP model, what the model
// holds beyond it (ids, keypoint indices, colours), handed back to WriteColmapModel. The Python
// API never removes images, points or marks; georeferencing (prepare_georeference,
// georeference_block) appends the control after them, so the extras describe the block's first
// points and marks: write_adjusted_colmap_model writes that part (ModelPartOfBlock).
struct PythonBlock {
  Block block;
  std::optional<ColmapModelExtras> colmap;
};

// ------------------------------------------------------------------ progress
// A Python progress callback (None, or a callable taking one Info: a BundleIterationInfo from the
// adjustments, a ResectionProgress from resect_images; anything else is a TypeError), called from
// the library's threads with the GIL taken for the call alone. The first exception it raises stops
// further calls and is raised again when the call returns. It cancels the call, as the callback
// returning False does: resect_images' images not yet started, the adjustment (Ceres or Taylor)
// after the iteration (termination "cancelled").
class ProgressRelay {
 public:
  // `takes` names what the callback receives, for the TypeError ("a BundleIterationInfo").
  explicit ProgressRelay(py::object callback, const char* takes = "a BundleIterationInfo")
      : callback_(std::move(callback)) {
    if (!callback_.is_none() && !PyCallable_Check(callback_.ptr()))
      throw py::type_error(std::string("progress: expected a callable taking ") + takes);
  }
  ~ProgressRelay() {
    py::gil_scoped_acquire acquire;
    callback_ = py::object();
  }

  bool active() const { return !callback_.is_none(); }

  // Calls the callback with `info` (a no-op without one or after it raised). Any thread, with or
  // without the GIL. Returns whether to go on: false once the callback has raised or when it
  // returned False.
  template <typename Info>
  bool Call(const Info& info) {
    if (!active()) return true;
    py::gil_scoped_acquire acquire;
    if (error_) return false;
    try {
      return callback_(info).ptr() != Py_False;
    } catch (py::error_already_set& e) {
      error_ = std::make_unique<py::error_already_set>(std::move(e));
      return false;
    }
  }
  // The hook of a library call that reports Info and may be cancelled (it returns what Call
  // returns): empty without a callback.
  template <typename Info = BundleIterationInfo>
  std::function<bool(const Info&)> Function() {
    if (!active()) return {};
    return [this](const Info& info) { return Call(info); };
  }
  // Raises the callback's exception, if any (with the GIL held).
  void Rethrow() {
    if (error_) throw std::move(*error_);
  }

 private:
  py::object callback_;
  std::unique_ptr<py::error_already_set> error_;
};

// ------------------------------------------------------------------ library calls
// Runs a library call (returning Status) without the GIL, so that other Python threads run
// meanwhile; then raises, in this order, the progress callback's exception (when a relay is given)
// and the call's failed Status as photopose.Error.
template <typename Call>
void CallWithoutGil(Call call, ProgressRelay* relay = nullptr) {
  Status status;
  {
    py::gil_scoped_release release;
    status = call();
  }
  if (relay != nullptr) relay->Rethrow();
  ThrowIfError(status);
}

// ------------------------------------------------------------------ the areas of the module
void BindGeometry(py::module_& m);
void BindResection(py::module_& m);
void BindBlock(py::module_& m);
void BindBundle(py::module_& m);
void BindGeoreference(py::module_& m);

}  // namespace photopose::python

// ------------------------------------------------------------------ enums as str
// Every enum with a name table in the library crosses into Python as its name ("huber", "opk",
// "SIMPLE_RADIAL") and back; an unknown name raises ValueError listing the accepted ones
// (EnumChoices), so that the names and aliases of the CLI and the tables are the module's too.
namespace pybind11::detail {

template <typename Enum>
struct PhotoposeEnumCaster {
  PYBIND11_TYPE_CASTER(Enum, const_name("str"));
  bool load(handle src, bool) {
    if (!src || !PyUnicode_Check(src.ptr())) return false;
    const std::string text = src.cast<std::string>();
    if (!photopose::ParseEnum(text, &value)) {
      throw value_error("unknown name '" + text + "': expected " +
                        photopose::EnumChoices<Enum>());
    }
    return true;
  }
  static handle cast(Enum value, return_value_policy, handle) {
    return str(photopose::EnumName(value)).release();
  }
};

#define PHOTOPOSE_PYTHON_ENUM(Enum) \
  template <>                       \
  struct type_caster<Enum> : PhotoposeEnumCaster<Enum> {};

PHOTOPOSE_PYTHON_ENUM(photopose::RotationConvention)
PHOTOPOSE_PYTHON_ENUM(photopose::CameraModelType)
PHOTOPOSE_PYTHON_ENUM(photopose::PixelOrigin)
PHOTOPOSE_PYTHON_ENUM(photopose::PixelRows)
PHOTOPOSE_PYTHON_ENUM(photopose::PointRole)
PHOTOPOSE_PYTHON_ENUM(photopose::MarkUnit)
PHOTOPOSE_PYTHON_ENUM(photopose::SolverTermination)
PHOTOPOSE_PYTHON_ENUM(photopose::JacobianType)
PHOTOPOSE_PYTHON_ENUM(photopose::LossType)
PHOTOPOSE_PYTHON_ENUM(photopose::PoseSolver)
PHOTOPOSE_PYTHON_ENUM(photopose::CeresMinimizer)
PHOTOPOSE_PYTHON_ENUM(photopose::TaylorPartials)
PHOTOPOSE_PYTHON_ENUM(photopose::MarkStatus)
PHOTOPOSE_PYTHON_ENUM(photopose::BundleLinearSolver)
PHOTOPOSE_PYTHON_ENUM(photopose::BundleDatum)
PHOTOPOSE_PYTHON_ENUM(photopose::BundleGroup)
PHOTOPOSE_PYTHON_ENUM(photopose::ColmapFormat)
PHOTOPOSE_PYTHON_ENUM(photopose::BundleCovarianceMethod)
PHOTOPOSE_PYTHON_ENUM(photopose::BundleRelativeCovariance)
PHOTOPOSE_PYTHON_ENUM(photopose::BundleCrossValidationMethod)

#undef PHOTOPOSE_PYTHON_ENUM

}  // namespace pybind11::detail
