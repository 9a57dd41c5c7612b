// Library buffers as numpy arrays, and numpy arrays into library buffers.
//
// Out: an array is a view of the library's own vector, never a copy; its base
// is the Python object that owns the vector (a Mesh), or a capsule holding a
// std::shared_ptr to it (the OrientedPoints load_points() returns), so the
// memory lives as long as any view of it does. Positions are
// std::vector<Vec3f> (Eigen's Vector3f is 12 packed bytes), triangles
// std::array<int32_t, 3>, colours std::array<uint8_t, 3>: all already
// row-major (n, 3) blocks. Triangles are shown as uint32, the same bits
// (indices are never negative).
//
// In: one pass, numpy.copyto() from the caller's array (any layout, any dtype
// numpy casts safely to the target's kind) straight into the vector the
// library will use, converting as it copies: a float32 array costs one
// memcpy-speed copy, a float64 or strided one no more passes than that.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstddef>
#include <memory>
#include <string>

namespace scan2lod::python {

namespace py = pybind11;

namespace internal {
template <typename T>
void release_owner(PyObject* capsule) {
  delete static_cast<std::shared_ptr<T>*>(PyCapsule_GetPointer(capsule, PyCapsule_GetName(capsule)));
}
}  // namespace internal

// A capsule named `name` that keeps `owner` alive until it is collected.
template <typename T>
py::capsule owner_capsule(std::shared_ptr<T> owner, const char* name) {
  return py::capsule(new std::shared_ptr<T>(std::move(owner)), name, &internal::release_owner<T>);
}

// The owner kept alive by `array`'s base when that is a capsule named
// `name` (numpy collapses a view of a view onto the same base, so slices
// answer too: callers compare data pointers and shapes); null otherwise.
template <typename T>
std::shared_ptr<T> owner_of(const py::array& array, const char* name) {
  const py::handle base = array.base();
  if (!base || !PyCapsule_CheckExact(base.ptr()) || !PyCapsule_IsValid(base.ptr(), name)) return nullptr;
  return *static_cast<std::shared_ptr<T>*>(PyCapsule_GetPointer(base.ptr(), name));
}

// A writable (rows, columns) view of `data`, row-major, with `base` as the
// array's base. Element is the numpy dtype's C type (uint32 for triangles).
template <typename Element>
py::array_t<Element> rows_view(const void* data, std::size_t rows, std::size_t columns, py::handle base) {
  return py::array_t<Element>({py::ssize_t(rows), py::ssize_t(columns)}, static_cast<const Element*>(data), base);
}

// `source` as an array of shape (n, columns), without copying an array:
// throws ValueError naming `what` ("points", "triangles") and the shape it
// got, and TypeError for a dtype that is not a number.
py::array require_rows(const py::handle& source, std::size_t columns, const std::string& what);

// Whether `array` is exactly the C-contiguous float32 rows at `data`, all
// `rows` of them (a view rows_view() made, not a slice of one).
bool views_floats(const py::array& array, const void* data, std::size_t rows);

// Copies `source`, of shape (rows, columns) as require_rows() checked, into
// `destination` (rows * columns elements of Element, row-major) in one pass,
// casting as numpy's `casting` rule allows ("same_kind", "unsafe"); raises
// TypeError naming `what` for a cast the rule forbids.
template <typename Element>
void copy_rows(const py::array& source, void* destination, std::size_t rows, std::size_t columns,
               const char* casting, const std::string& what) {
  if (rows == 0) return;
  // A view only for this call, with the GIL held. It needs a base all the
  // same: without one pybind11 copies `destination` into a new array.
  py::array_t<Element> into({py::ssize_t(rows), py::ssize_t(columns)}, static_cast<Element*>(destination),
                            py::none());
  const py::module_ numpy = py::module_::import("numpy");
  const py::object allowed = numpy.attr("can_cast")(source.dtype(), into.dtype(), py::arg("casting") = casting);
  if (!py::cast<bool>(allowed))
    throw py::type_error(what + " must hold " + py::str(into.dtype()).cast<std::string>() + " values, got " +
                         py::str(source.dtype()).cast<std::string>());
  numpy.attr("copyto")(into, source, py::arg("casting") = casting);
}

}  // namespace scan2lod::python
