// The photopose module: its exception, the shared conversions of common.h, and the areas bound in
// geometry.cc, resection.cc, block.cc and bundle.cc.

#include <sstream>

#include "common.h"

namespace photopose::python {

std::string PathArgument(const py::handle& path, const char* name) {
  if (path.is_none()) throw py::type_error(std::string(name) + ": expected a path, got None");
  py::object text = py::module_::import("os").attr("fspath")(path);
  if (!py::isinstance<py::str>(text))
    throw py::type_error(std::string(name) + ": expected a str path, got bytes");
  return text.cast<std::string>();
}

namespace {

std::string ShapeText(const py::array& a) {
  std::string text = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) {
    if (i > 0) text += ", ";
    text += std::to_string(a.shape(i));
  }
  return text + (a.ndim() == 1 ? ",)" : ")");
}

// A float64 C-ordered array of `value`, or ValueError naming `name` when it holds no numbers.
py::array_t<double, py::array::c_style> AsFloatArray(const py::handle& value, const char* name,
                                                     const std::string& expected) {
  if (value.is_none())
    throw py::value_error(std::string(name) + ": expected " + expected + ", got None");
  // Refuse text and objects before numpy would turn "1.5" into 1.5 or fail deep inside.
  py::array given = py::array::ensure(value);
  if (!given) {
    PyErr_Clear();
    throw py::value_error(std::string(name) + ": expected " + expected + ", got " +
                          std::string(py::str(py::type::of(value).attr("__name__"))));
  }
  const char kind = given.dtype().kind();
  if (given.size() > 0 && kind != 'f' && kind != 'i' && kind != 'u' && kind != 'b') {
    throw py::value_error(std::string(name) + ": expected " + expected + " of numbers, got dtype " +
                          std::string(py::str(given.dtype())));
  }
  auto converted = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(given);
  if (!converted) {
    PyErr_Clear();
    throw py::value_error(std::string(name) + ": cannot convert dtype " +
                          std::string(py::str(given.dtype())) + " to float64");
  }
  return converted;
}

}  // namespace

py::array_t<double, py::array::c_style> Matrix(const py::handle& value, const char* name,
                                               int columns) {
  const std::string expected = "an N x " + std::to_string(columns) + " array";
  auto a = AsFloatArray(value, name, expected);
  if (a.size() == 0)
    return py::array_t<double, py::array::c_style>(std::vector<py::ssize_t>{0, py::ssize_t(columns)});
  if (a.ndim() == 1 && a.shape(0) == columns) return a.reshape({py::ssize_t(1), py::ssize_t(columns)});
  if (a.ndim() != 2 || a.shape(1) != columns)
    throw py::value_error(std::string(name) + ": expected " + expected + ", got shape " +
                          ShapeText(a));
  return a;
}

std::vector<double> Vector(const py::handle& value, const char* name, long n, bool broadcast) {
  const std::string expected = n >= 0 ? "a vector of " + std::to_string(n) + " numbers" : "a vector";
  auto a = AsFloatArray(value, name, expected);
  if (a.ndim() == 0) {
    if (!broadcast) throw py::value_error(std::string(name) + ": expected " + expected + ", got a scalar");
    return std::vector<double>(n >= 0 ? n : 1, *a.data());
  }
  if (a.ndim() != 1 || (n >= 0 && a.shape(0) != n))
    throw py::value_error(std::string(name) + ": expected " + expected + ", got shape " + ShapeText(a));
  return std::vector<double>(a.data(), a.data() + a.size());
}

std::vector<Eigen::Vector2d> Points2(const py::handle& value, const char* name) {
  auto a = Matrix(value, name, 2);
  std::vector<Eigen::Vector2d> rows(a.shape(0));
  const double* d = a.data();
  for (size_t i = 0; i < rows.size(); ++i) rows[i] = Eigen::Vector2d(d[2 * i], d[2 * i + 1]);
  return rows;
}

std::vector<Eigen::Vector3d> Points3(const py::handle& value, const char* name) {
  auto a = Matrix(value, name, 3);
  std::vector<Eigen::Vector3d> rows(a.shape(0));
  const double* d = a.data();
  for (size_t i = 0; i < rows.size(); ++i)
    rows[i] = Eigen::Vector3d(d[3 * i], d[3 * i + 1], d[3 * i + 2]);
  return rows;
}

Eigen::Vector3d Vector3(const py::handle& value, const char* name) {
  const std::vector<double> v = Vector(value, name, 3, false);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

Eigen::Matrix3d Matrix3(const py::handle& value, const char* name) {
  auto a = AsFloatArray(value, name, "a 3 x 3 array");
  if (a.ndim() != 2 || a.shape(0) != 3 || a.shape(1) != 3)
    throw py::value_error(std::string(name) + ": expected a 3 x 3 array, got shape " + ShapeText(a));
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = a.at(r, c);
  return m;
}

std::vector<std::string> Strings(const py::handle& value, const char* name) {
  std::vector<std::string> out;
  if (value.is_none()) return out;
  if (py::isinstance<py::str>(value))
    throw py::value_error(std::string(name) + ": expected a sequence of str, got one str");
  for (const py::handle item : py::iter(value)) {
    if (!py::isinstance<py::str>(item))
      throw py::value_error(std::string(name) + ": expected str items, got " +
                            std::string(py::str(py::type::of(item).attr("__name__"))));
    out.push_back(item.cast<std::string>());
  }
  return out;
}

py::array_t<double> ToArray(const std::vector<Eigen::Vector2d>& rows) {
  py::array_t<double> out({static_cast<py::ssize_t>(rows.size()), py::ssize_t(2)});
  double* d = out.mutable_data();
  for (size_t i = 0; i < rows.size(); ++i) {
    d[2 * i] = rows[i].x();
    d[2 * i + 1] = rows[i].y();
  }
  return out;
}

py::array_t<double> ToArray(const std::vector<Eigen::Vector3d>& rows) {
  py::array_t<double> out({static_cast<py::ssize_t>(rows.size()), py::ssize_t(3)});
  double* d = out.mutable_data();
  for (size_t i = 0; i < rows.size(); ++i)
    for (int k = 0; k < 3; ++k) d[3 * i + k] = rows[i][k];
  return out;
}

py::array_t<bool> ToBoolArray(const std::vector<char>& flags) {
  py::array_t<bool> out(static_cast<py::ssize_t>(flags.size()));
  for (size_t i = 0; i < flags.size(); ++i) out.mutable_data()[i] = flags[i] != 0;
  return out;
}

namespace {

// The names of the properties of `self`'s class (and its bases), in declaration order.
std::vector<std::string> PropertyNames(const py::handle& self) {
  std::vector<std::string> names;
  py::object property = py::module_::import("builtins").attr("property");
  py::object type = py::type::of(self);
  for (const py::handle base : type.attr("__mro__")) {
    py::dict dict = base.attr("__dict__");
    for (const auto& item : dict) {
      const std::string name = item.first.cast<std::string>();
      if (name.empty() || name[0] == '_') continue;
      if (!py::isinstance(item.second, property)) continue;
      if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
    }
  }
  return names;
}

}  // namespace

std::string PropertiesRepr(const py::handle& self) {
  std::string text = std::string(py::str(py::type::of(self).attr("__name__"))) + "(";
  bool first = true;
  for (const std::string& name : PropertyNames(self)) {
    if (!first) text += ", ";
    first = false;
    py::object value = self.attr(name.c_str());
    std::string shown;
    if (py::isinstance<py::array>(value)) {
      shown = std::string(py::repr(value.attr("tolist")()));
    } else {
      shown = std::string(py::repr(value));
    }
    text += name + "=" + shown;
  }
  return text + ")";
}

void SetKeywordAttributes(const py::handle& self, const py::kwargs& kwargs) {
  const std::vector<std::string> names = PropertyNames(self);
  for (const auto& item : kwargs) {
    const std::string key = item.first.cast<std::string>();
    if (std::find(names.begin(), names.end(), key) == names.end()) {
      std::string known;
      for (const std::string& name : names) known += (known.empty() ? "" : ", ") + name;
      throw py::type_error(std::string(py::str(py::type::of(self).attr("__name__"))) +
                           "() got an unexpected keyword argument '" + key + "' (fields: " +
                           known + ")");
    }
    py::setattr(self, item.first, item.second);
  }
}

}  // namespace photopose::python

PYBIND11_MODULE(_photopose, m) {
  namespace pp = photopose::python;
  m.doc() =
      "photopose: camera poses from the collinearity equations (resection, weighted bundle "
      "adjustment with honest statistics). The C++ library's objects and calls; docs/python.md.";
  // Every failed Status of the library: a ValueError whose text is the Status' message.
  m.attr("__version__") = PHOTOPOSE_VERSION;
  pybind11::register_exception<pp::StatusError>(m, "Error", PyExc_ValueError);
  pp::BindGeometry(m);
  pp::BindResection(m);
  pp::BindBlock(m);
  pp::BindBundle(m);
  pp::BindGeoreference(m);
}
