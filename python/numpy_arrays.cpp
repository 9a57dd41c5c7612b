#include <scan2lod/python/numpy_arrays.h>

namespace scan2lod::python {

py::array require_rows(const py::handle& source, std::size_t columns, const std::string& what) {
  // asarray() returns an array argument itself; lists become one array.
  py::array array = py::module_::import("numpy").attr("asarray")(source);
  if (array.ndim() != 2 || array.shape(1) != py::ssize_t(columns)) {
    std::string shape = "(";
    for (py::ssize_t d = 0; d < array.ndim(); ++d) shape += (d ? ", " : "") + std::to_string(array.shape(d));
    if (array.ndim() == 1) shape += ",";
    throw py::value_error(what + " must be an (n, " + std::to_string(columns) + ") array, got shape " + shape + ")");
  }
  const char kind = array.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw py::type_error(what + " must hold numbers, got dtype " + py::str(array.dtype()).cast<std::string>());
  return array;
}

bool views_floats(const py::array& array, const void* data, std::size_t rows) {
  return array.data() == data && array.shape(0) == py::ssize_t(rows) && array.dtype().kind() == 'f' &&
         array.dtype().itemsize() == 4 && (array.flags() & py::array::c_style) != 0;
}

}  // namespace scan2lod::python
