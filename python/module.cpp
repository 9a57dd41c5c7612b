// The Python package's native module, scan2lod._scan2lod: the library's
// faces for a Python user, arrays as numpy views (python/numpy_arrays.h).
#include <scan2lod/python/bindings.h>
#include <scan2lod/python/errors.h>

PYBIND11_MODULE(_scan2lod, m) {
  m.doc() = "scan2lod: range scans -> marching-cubes meshes -> level-of-detail models";
  m.attr("__version__") = SCAN2LOD_VERSION;
  scan2lod::python::register_error_translation(m);
  scan2lod::python::bind_mesh(m);
  scan2lod::python::bind_points(m);
  scan2lod::python::bind_reconstruct(m);
  scan2lod::python::bind_model(m);
  scan2lod::python::bind_compare(m);
}
