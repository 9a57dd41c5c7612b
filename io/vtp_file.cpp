#include <scan2lod/io/vtp_file.h>

#include <scan2lod/core/error.h>

#include <vtkCallbackCommand.h>
#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkCommand.h>
#include <vtkDoubleArray.h>
#include <vtkExecutive.h>
#include <vtkFloatArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkTypeInt32Array.h>
#include <vtkUnsignedCharArray.h>
#include <vtkXMLDataElement.h>
#include <vtkXMLDataParser.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>

#include <cstring>
#include <filesystem>
#include <functional>
#include <string>

namespace scan2lod {
namespace {

// Collects VTK error messages so that they end up in our exception, not on stderr.
class VtkErrorCatcher {
 public:
  VtkErrorCatcher() {
    callback_->SetClientData(&message_);
    callback_->SetCallback([](vtkObject*, unsigned long, void* client, void* call) {
      auto* message = static_cast<std::string*>(client);
      if (message->empty() && call) *message = static_cast<const char*>(call);
    });
  }
  // Errors become the exception's message; warnings (a malformed optional
  // array, say) only mean that attribute is left out.
  void watch(vtkObject* object) {
    object->AddObserver(vtkCommand::ErrorEvent, callback_);
    object->AddObserver(vtkCommand::WarningEvent, ignore_);
  }
  vtkCommand* command() { return callback_; }
  const std::string& message() const { return message_; }

 private:
  std::string message_;
  vtkNew<vtkCallbackCommand> callback_;
  vtkNew<vtkCallbackCommand> ignore_;  // no callback set: does nothing
};

std::string first_line(std::string s) {
  std::size_t eol = s.find('\n');
  if (eol != std::string::npos) s.resize(eol);
  return s;
}

// Parses an XML count attribute as VTK would accept it; false when it is not
// a plain integer (VTK would read "3444...4" as INT_MAX, "7x" as 7).
bool vtk_count(vtkXMLDataElement* e, const char* name, long long fallback, long long& value) {
  const char* text = e->GetAttribute(name);
  if (!text) {
    value = fallback;
    return true;
  }
  errno = 0;
  char* end = nullptr;
  value = std::strtoll(text, &end, 10);
  while (end && std::isspace(static_cast<unsigned char>(*end))) ++end;
  return end != text && *end == '\0' && errno == 0 && value >= 0;
}

// VTK sizes its arrays by the XML's counts before it reads any data (a
// 400-byte file asked for 4.8 GB by NumberOfPoints), and loops over a
// "ComponentName<i>" attribute per component (a NumberOfComponents of 2^31
// hangs for minutes). So the arrays the counts imply must fit the file: a
// value takes at least a byte, or a 10000th of one when compressed.
void check_vtp_counts(const std::string& path, vtkXMLDataElement* root) {
  std::error_code ec;
  std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) size = 0;
  const bool compressed = root->GetAttribute("compressor") != nullptr;
  const long double budget = (long double)size * (compressed ? 10000.0L : 1.0L) + 1024.0L;
  long double values = 0;
  auto too_many = [&](const std::string& what) {
    return InputError(path, what + ": more values than a file of " + std::to_string(size) +
                                " bytes can hold");
  };
  // Per piece: points, then verts, lines, strips, polys.
  struct Counts {
    long long n[5] = {0, 0, 0, 0, 0};
  };
  const char* const kPieceCounts[5] = {"NumberOfPoints", "NumberOfVerts", "NumberOfLines",
                                       "NumberOfStrips", "NumberOfPolys"};
  const char* const kCellKinds[4] = {"Verts", "Lines", "Strips", "Polys"};
  std::function<void(vtkXMLDataElement*, const std::string&, const Counts&)> walk =
      [&](vtkXMLDataElement* e, const std::string& parent, const Counts& outer) {
        const std::string name = e->GetName() ? e->GetName() : "";
        Counts piece = outer;
        if (name == "Piece") {
          for (int k = 0; k < 5; ++k) {
            if (!vtk_count(e, kPieceCounts[k], 0, piece.n[k]))
              throw InputError(path, "Piece " + std::string(kPieceCounts[k]) + "=\"" +
                                         e->GetAttribute(kPieceCounts[k]) + "\": expected a count");
            if ((long double)piece.n[k] > budget)
              throw too_many("Piece " + std::string(kPieceCounts[k]) + "=" + std::to_string(piece.n[k]));
          }
        } else if (name == "DataArray" || name == "Array") {
          const char* array = e->GetAttribute("Name");
          const std::string what = name + (array ? " '" + std::string(array) + "'" : std::string());
          long long components = 1, tuples = 0;
          if (!vtk_count(e, "NumberOfComponents", 1, components) || components < 1 ||
              components > 10000)
            throw InputError(path, what + " NumberOfComponents=\"" +
                                       e->GetAttribute("NumberOfComponents") + "\": expected 1 to 10000");
          const long long cells = piece.n[1] + piece.n[2] + piece.n[3] + piece.n[4];
          if (parent == "Points" || parent == "PointData") tuples = piece.n[0];
          else if (parent == "CellData") tuples = cells;
          else if (!vtk_count(e, "NumberOfTuples", 0, tuples))
            throw InputError(path, what + " NumberOfTuples=\"" + e->GetAttribute("NumberOfTuples") +
                                       "\": expected a count");
          for (int k = 0; k < 4; ++k)  // a cell array's offsets: one per cell
            if (parent == kCellKinds[k] && array && std::string(array) == "offsets") tuples = piece.n[k + 1];
          values += (long double)tuples * (long double)components;
          if (values > budget)
            throw too_many(what + " of " + std::to_string(tuples) + " x " + std::to_string(components));
        }
        for (int i = 0; i < e->GetNumberOfNestedElements(); ++i) walk(e->GetNestedElement(i), name, piece);
      };
  walk(root, "", Counts{});
}

}  // namespace

// With `exact`, the points in double as well (VTK hands them over as doubles).
TriangleMesh read_vtp(const std::string& path, std::vector<Vec3d>* exact) {
  VtkErrorCatcher errors;  // outlives the reader that reports to it
  vtkNew<vtkXMLPolyDataReader> reader;
  if (!reader->CanReadFile(path.c_str()))
    throw InputError(path, "not a VTK XML PolyData (.vtp) file");
  errors.watch(reader);
  errors.watch(reader->GetExecutive());
  reader->SetParserErrorObserver(errors.command());
  reader->SetReaderErrorObserver(errors.command());
  reader->SetFileName(path.c_str());
  try {
    reader->UpdateInformation();  // parses the XML, reads no data
  } catch (const std::exception& e) {
    throw InputError(path, std::string("cannot parse as vtp: ") + e.what());
  }
  if (!errors.message().empty() || reader->GetErrorCode() != 0)
    throw InputError(path, "cannot parse as vtp: " + first_line(errors.message()));
  if (vtkXMLDataParser* parser = reader->GetXMLParser())
    if (vtkXMLDataElement* root = parser->GetRootElement()) check_vtp_counts(path, root);
  try {
    reader->Update();
  } catch (const std::exception& e) {  // e.g. bad_alloc for a garbled array size
    throw InputError(path, std::string("cannot parse as vtp: ") + e.what());
  }
  vtkPolyData* poly = reader->GetOutput();
  if (!errors.message().empty() || reader->GetErrorCode() != 0 || !poly)
    throw InputError(path, "cannot parse as vtp: " + first_line(errors.message()));

  TriangleMesh mesh;
  const vtkIdType n = poly->GetNumberOfPoints();
  mesh.positions.resize(std::size_t(n));
  if (exact) exact->resize(std::size_t(n));
  for (vtkIdType i = 0; i < n; ++i) {
    double p[3];
    poly->GetPoint(i, p);
    mesh.positions[std::size_t(i)] = Vec3f(float(p[0]), float(p[1]), float(p[2]));
    if (exact) (*exact)[std::size_t(i)] = Vec3d(p[0], p[1], p[2]);
  }
  auto add_cells = [&](vtkCellArray* cells, bool strip) {
    if (!cells) return;
    auto it = vtk::TakeSmartPointer(cells->NewIterator());
    for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell()) {
      vtkIdType count;
      const vtkIdType* ids;
      it->GetCurrentCell(count, ids);
      for (vtkIdType k = 0; k < count; ++k)
        if (ids[k] < 0 || ids[k] >= n)
          throw InputError(path, "a cell names point " + std::to_string(ids[k]) +
                                     " but the file has " + std::to_string(n) + " points");
      for (vtkIdType k = 0; k + 2 < count; ++k) {
        if (strip)  // every other strip triangle is wound the other way
          mesh.triangles.push_back(
              k % 2 == 0 ? Triangle{int(ids[k]), int(ids[k + 1]), int(ids[k + 2])}
                         : Triangle{int(ids[k + 1]), int(ids[k]), int(ids[k + 2])});
        else
          mesh.triangles.push_back({int(ids[0]), int(ids[k + 1]), int(ids[k + 2])});
      }
    }
  };
  add_cells(poly->GetPolys(), false);
  add_cells(poly->GetStrips(), true);

  vtkPointData* pd = poly->GetPointData();
  vtkDataArray* normals = pd->GetNormals() ? pd->GetNormals() : pd->GetArray("Normals");
  if (normals && normals->GetNumberOfComponents() == 3 && normals->GetNumberOfTuples() == n) {
    mesh.normals.resize(std::size_t(n));
    for (vtkIdType i = 0; i < n; ++i) {
      double v[3];
      normals->GetTuple(i, v);
      mesh.normals[std::size_t(i)] = Vec3f(float(v[0]), float(v[1]), float(v[2]));
    }
  }
  vtkDataArray* colors = pd->GetArray("RGB") ? pd->GetArray("RGB") : pd->GetScalars();
  if (colors && (colors->GetNumberOfComponents() == 3 || colors->GetNumberOfComponents() == 4) &&
      colors->GetNumberOfTuples() == n) {
    // Byte colours are 0..255; floating-point colours are taken as 0..1.
    const bool bytes = colors->GetDataType() == VTK_UNSIGNED_CHAR;
    mesh.colors.resize(std::size_t(n));
    for (vtkIdType i = 0; i < n; ++i) {
      double v[4];
      colors->GetTuple(i, v);
      for (int c = 0; c < 3; ++c)
        mesh.colors[std::size_t(i)][c] = std::uint8_t(
            std::lround(std::clamp(bytes ? v[c] : v[c] * 255.0, 0.0, 255.0)));
    }
  }
  return mesh;
}

void write_vtp(const std::string& tmp, const std::string& final_path, const TriangleMesh& mesh,
               const Vec3d& origin) {
  const vtkIdType n = vtkIdType(mesh.positions.size());
  vtkNew<vtkPoints> points;
  if (origin == Vec3d::Zero()) {
    vtkNew<vtkFloatArray> coords;
    coords->SetNumberOfComponents(3);
    coords->SetNumberOfTuples(n);
    if (n) std::memcpy(coords->GetPointer(0), mesh.positions.data(), std::size_t(n) * sizeof(Vec3f));
    points->SetData(coords);
  } else {  // Float64 points in the file's frame
    vtkNew<vtkDoubleArray> coords;
    coords->SetNumberOfComponents(3);
    coords->SetNumberOfTuples(n);
    double* out = coords->GetPointer(0);
    for (vtkIdType i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) out[3 * i + k] = origin[k] + double(mesh.positions[std::size_t(i)][k]);
    points->SetData(coords);
  }

  vtkNew<vtkTypeInt32Array> connectivity;
  connectivity->SetNumberOfValues(vtkIdType(mesh.triangles.size() * 3));
  if (!mesh.triangles.empty())
    std::memcpy(connectivity->GetPointer(0), mesh.triangles.data(),
                mesh.triangles.size() * sizeof(Triangle));
  vtkNew<vtkCellArray> polys;
  polys->SetData(3, connectivity);

  vtkNew<vtkPolyData> poly;
  poly->SetPoints(points);
  poly->SetPolys(polys);
  if (!mesh.normals.empty()) {
    vtkNew<vtkFloatArray> normals;
    normals->SetName("Normals");
    normals->SetNumberOfComponents(3);
    normals->SetNumberOfTuples(n);
    std::memcpy(normals->GetPointer(0), mesh.normals.data(), std::size_t(n) * sizeof(Vec3f));
    poly->GetPointData()->SetNormals(normals);
  }
  if (!mesh.colors.empty()) {
    vtkNew<vtkUnsignedCharArray> rgb;
    rgb->SetName("RGB");
    rgb->SetNumberOfComponents(3);
    rgb->SetNumberOfTuples(n);
    std::memcpy(rgb->GetPointer(0), mesh.colors.data(), std::size_t(n) * sizeof(Rgb));
    poly->GetPointData()->SetScalars(rgb);
  }

  VtkErrorCatcher errors;  // outlives the writer that reports to it
  vtkNew<vtkXMLPolyDataWriter> writer;
  errors.watch(writer);
  errors.watch(writer->GetExecutive());
  writer->SetFileName(tmp.c_str());
  writer->SetInputData(poly);
  // Raw appended binary, uncompressed: several times faster than the
  // zlib/base64 default, and VTK's reader crashes on damaged compressed
  // blocks while it reports damaged raw ones.
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  writer->SetCompressorTypeToNone();
  if (writer->Write() != 1 || writer->GetErrorCode() != 0 || !errors.message().empty())
    throw InputError(final_path, "writing vtp failed: " + first_line(errors.message()));
}

}  // namespace scan2lod
