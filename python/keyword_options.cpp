#include <scan2lod/python/keyword_options.h>

#include <scan2lod/reconstruct/signed_distance.h>

namespace scan2lod::python {
namespace py = pybind11;

KeywordOptions::KeywordOptions(const py::kwargs& options, std::string function)
    : left_(py::dict(options)), function_(std::move(function)) {}

ReconstructOptions KeywordOptions::reconstruct(int resolution, int threads) {
  if (threads < 0)
    throw py::value_error("threads: expected 0 (all cores) or a positive count, got " + std::to_string(threads));
  ReconstructOptions o;
  o.resolution = resolution;
  o.threads = threads;
  take("margin", &o.margin);
  std::string distance;
  if (take("distance", &distance)) o.distance.method = parse_distance_method(distance);
  take("neighbours", &o.distance.neighbours);
  take("max_distance", &o.distance.max_distance);
  take("reach", &o.reach);
  take("min_piece", &o.min_piece);
  take("max_hole", &o.max_hole);
  take("hole_rounds", &o.hole_rounds);
  return o;
}

void KeywordOptions::refuse_unknown() const {
  for (const auto& item : left_)
    throw py::type_error(function_ + "() got an unexpected keyword argument '" + py::str(item.first).cast<std::string>() +
                         "'");
}

}  // namespace scan2lod::python
