#include <sflsh/core/array_units.hpp>
#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/vtk_io.hpp>

#include <Eigen/Geometry>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkFloatArray.h>
#include <vtkIdList.h>
#include <vtkIntArray.h>
#include <vtkLZ4DataCompressor.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPointSet.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>
#include <vtkZLibDataCompressor.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace sflsh::vtk {

namespace {

vtkSmartPointer<vtkPoints> make_points(const Eigen::Ref<const Points>& points) {
  require(points.allFinite(), "refusing to write non-finite point coordinates");
  auto out = vtkSmartPointer<vtkPoints>::New();
  out->SetDataTypeToDouble();
  out->SetNumberOfPoints(points.rows());
  for (Eigen::Index i = 0; i < points.rows(); ++i) out->SetPoint(i, points(i, 0), points(i, 1), points(i, 2));
  return out;
}

vtkSmartPointer<vtkDataArray> make_array(const Field& field, Eigen::Index expected_rows, const char* where) {
  require(field.values.rows() == expected_rows, "{} array '{}' has {} rows, expected {}", where, field.name,
          field.values.rows(), expected_rows);
  require(field.values.allFinite(), "{} array '{}' holds non-finite values", where, field.name);
  vtkSmartPointer<vtkDataArray> array;
  if (field.integer)
    array = vtkSmartPointer<vtkIntArray>::New();
  else
    array = vtkSmartPointer<vtkDoubleArray>::New();
  array->SetName(field.name.c_str());
  array->SetNumberOfComponents(static_cast<int>(field.values.cols()));
  array->SetNumberOfTuples(field.values.rows());
  const Eigen::Index rows = field.values.rows(), cols = field.values.cols();
  // Straight into the arrays' memory (row-major tuples); SetComponent per value is a virtual call each.
  if (field.integer) {
    int* out = static_cast<vtkIntArray*>(array.Get())->GetPointer(0);
    for (Eigen::Index r = 0; r < rows; ++r)
      for (Eigen::Index c = 0; c < cols; ++c) out[r * cols + c] = static_cast<int>(field.values(r, c));
  } else {
    double* out = static_cast<vtkDoubleArray*>(array.Get())->GetPointer(0);
    for (Eigen::Index r = 0; r < rows; ++r)
      for (Eigen::Index c = 0; c < cols; ++c) out[r * cols + c] = field.values(r, c);
  }
  return array;
}

vtkSmartPointer<vtkCellArray> make_cells(const Eigen::Ref<const Cells>& cells, Eigen::Index num_points) {
  auto out = vtkSmartPointer<vtkCellArray>::New();
  if (cells.rows() > 0) {
    require(cells.minCoeff() >= 0 && cells.maxCoeff() < num_points, "cell indexes point {}..{}, expected 0..{}",
            cells.minCoeff(), cells.maxCoeff(), num_points - 1);
  }
  std::vector<vtkIdType> ids(static_cast<std::size_t>(cells.cols()));
  for (Eigen::Index r = 0; r < cells.rows(); ++r) {
    for (Eigen::Index c = 0; c < cells.cols(); ++c) ids[static_cast<std::size_t>(c)] = cells(r, c);
    out->InsertNextCell(static_cast<vtkIdType>(ids.size()), ids.data());
  }
  return out;
}

/// A text array of field data (`units`, `part_names`, …): the values as UTF-8 text, one line each, in a UInt8
/// array. Not a string array: meshio's VTU reader refuses the type "String" (docs/output.md, "Units in the files").
vtkSmartPointer<vtkUnsignedCharArray> make_text(const std::string& name, const std::vector<std::string>& values) {
  std::string text;
  for (std::size_t k = 0; k < values.size(); ++k) {
    require(values[k].find('\n') == std::string::npos, "field data '{}': entry '{}' holds a line break", name,
            values[k]);
    text += (k == 0 ? "" : "\n") + values[k];
  }
  auto array = vtkSmartPointer<vtkUnsignedCharArray>::New();
  array->SetName(name.c_str());
  array->SetNumberOfComponents(1);
  array->SetNumberOfTuples(static_cast<vtkIdType>(text.size()));
  std::copy(text.begin(), text.end(), array->GetPointer(0));
  return array;
}

/// The `units` entries of every numeric array of the dataset, one per distinct name, in the order written
/// (before the text arrays are attached).
std::vector<std::string> unit_entries(vtkDataSet* data) {
  std::vector<std::string> names;
  for (vtkFieldData* group : {static_cast<vtkFieldData*>(data->GetPointData()),
                              static_cast<vtkFieldData*>(data->GetCellData()), data->GetFieldData()}) {
    for (int i = 0; i < group->GetNumberOfArrays(); ++i) {
      if (!group->GetArray(i) || !group->GetArrayName(i)) continue;
      const std::string name = group->GetArrayName(i);
      if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
    }
  }
  std::vector<std::string> entries;
  for (const std::string& name : names) entries.push_back(units::entry(name));
  return entries;
}

void attach_fields(vtkDataSet* data, const Fields& fields, Eigen::Index num_points, Eigen::Index num_cells) {
  for (const Field& f : fields.point_data) data->GetPointData()->AddArray(make_array(f, num_points, "point-data"));
  for (const Field& f : fields.cell_data) data->GetCellData()->AddArray(make_array(f, num_cells, "cell-data"));
  for (const Field& f : fields.field_data) data->GetFieldData()->AddArray(make_array(f, 1, "field-data"));
  if (vtkDataArray* normals = data->GetPointData()->GetArray("Normals");
      normals && normals->GetNumberOfComponents() == 3)
    data->GetPointData()->SetNormals(normals);
}

/// The `units` field data, after every numeric array is attached, then the label names.
void attach_units_and_labels(vtkDataSet* data, const Fields& fields) {
  const std::vector<std::string> entries = unit_entries(data);
  if (!entries.empty()) data->GetFieldData()->AddArray(make_text("units", entries));
  for (const Labels& l : fields.labels) data->GetFieldData()->AddArray(make_text(l.name, l.values));
}

vtkSmartPointer<vtkFloatArray> make_normals(const Eigen::Ref<const Points>& points,
                                            const Eigen::Ref<const Cells>& triangles) {
  const Points n = vertex_normals(points, triangles);
  auto array = vtkSmartPointer<vtkFloatArray>::New();
  array->SetName("Normals");
  array->SetNumberOfComponents(3);
  array->SetNumberOfTuples(n.rows());
  float* out = array->GetPointer(0);
  for (Eigen::Index i = 0; i < n.size(); ++i) out[i] = static_cast<float>(n.data()[i]);
  return array;
}

bool has_point_field(const Fields& fields, const char* name) {
  return std::any_of(fields.point_data.begin(), fields.point_data.end(),
                     [&](const Field& f) { return f.name == name; });
}

template <typename Writer>
void write_with(Writer* writer, vtkDataObject* data, const std::filesystem::path& path, Compression compression) {
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    // Into memory, then to the file with checked writes: VTK 9.1's XML writers, on a write error (a full disk,
    // a file size limit), free their position arrays twice and crash the process (issue 45).
    writer->WriteToOutputStringOn();
    writer->SetInputData(data);
    // Inline binary (base64 per array), not raw appended data: VTK 9.1–9.2.6's XML reader loses its place in
    // appended data under expat ≥ 2.6 (Debian 12's security update), so Debian's ParaView 5.11 reads appended
    // files as empty (docs/decisions.md). Inline binary is about a third larger and every reader opens it.
    writer->SetDataModeToBinary();
    vtkSmartPointer<vtkDataCompressor> compressor;
    if (compression == Compression::zlib)
      compressor = vtkSmartPointer<vtkZLibDataCompressor>::New();
    else if (compression == Compression::lz4)
      compressor = vtkSmartPointer<vtkLZ4DataCompressor>::New();
    if (compressor)
      writer->SetCompressor(compressor);
    else
      writer->SetCompressorTypeToNone();
    require(writer->Write() == 1, "{}: VTK writer failed", path.string());
    write_file_checked(tmp, path, writer->GetOutputString());
  });
}

vtkSmartPointer<vtkPointSet> read_any(const std::filesystem::path& path) {
  require(std::filesystem::exists(path), "{}: file not found", path.string());
  if (path.extension() == ".vtp") {
    vtkNew<vtkXMLPolyDataReader> reader;
    reader->SetFileName(path.c_str());
    reader->Update();
    require(reader->GetErrorCode() == 0 && reader->GetOutput(), "{}: VTK could not read the file", path.string());
    return reader->GetOutput();
  }
  require(path.extension() == ".vtu", "{}: expected a .vtp or .vtu file", path.string());
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  require(reader->GetErrorCode() == 0 && reader->GetOutput(), "{}: VTK could not read the file", path.string());
  return reader->GetOutput();
}

}  // namespace

Compression parse_compression(const std::string& name, const std::string& what) {
  if (name == "zlib") return Compression::zlib;
  if (name == "lz4") return Compression::lz4;
  if (name == "none") return Compression::none;
  throw_error("{} = '{}' is not one of zlib | lz4 | none", what, name);
}

const char* to_string(Compression compression) {
  switch (compression) {
    case Compression::zlib:
      return "zlib";
    case Compression::lz4:
      return "lz4";
    case Compression::none:
      return "none";
  }
  return "?";
}

void write_surface(const std::filesystem::path& path, const Eigen::Ref<const Points>& points,
                   const Eigen::Ref<const Cells>& triangles, const Fields& fields, Compression compression) {
  require(triangles.cols() == 3, "{}: surface cells need 3 vertices, got {}", path.string(), triangles.cols());
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(make_points(points));
  poly->SetPolys(make_cells(triangles, points.rows()));
  attach_fields(poly, fields, points.rows(), triangles.rows());
  if (fields.normals && triangles.rows() > 0 && !has_point_field(fields, "Normals")) {
    poly->GetPointData()->AddArray(make_normals(points, triangles));
    poly->GetPointData()->SetNormals(poly->GetPointData()->GetArray("Normals"));
  }
  attach_units_and_labels(poly, fields);
  vtkNew<vtkXMLPolyDataWriter> writer;
  write_with(writer.Get(), poly, path, compression);
}

void write_unstructured(const std::filesystem::path& path, const Eigen::Ref<const Points>& points,
                        const Eigen::Ref<const Cells>& cells, const Fields& fields, Compression compression) {
  require(cells.cols() == 3 || cells.cols() == 4, "{}: cells need 3 (triangle) or 4 (tetrahedron) vertices, got {}",
          path.string(), cells.cols());
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(make_points(points));
  grid->SetCells(cells.cols() == 4 ? VTK_TETRA : VTK_TRIANGLE, make_cells(cells, points.rows()));
  attach_fields(grid, fields, points.rows(), cells.rows());
  attach_units_and_labels(grid, fields);
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  write_with(writer.Get(), grid, path, compression);
}

void PvdSeries::write() const {
  std::ostringstream xml;
  xml << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n";
  for (const Entry& e : entries_) {
    xml << "    <DataSet";
    if (e.timed) xml << fmt::format(" timestep=\"{:.9g}\"", e.time);
    xml << fmt::format(" group=\"\" part=\"{}\"", e.part);
    if (!e.name.empty()) xml << fmt::format(" name=\"{}\"", e.name);
    xml << fmt::format(" file=\"{}\"/>\n", e.file);
  }
  xml << "  </Collection>\n</VTKFile>\n";
  write_text_atomically(path_, xml.str());
}

Points vertex_normals(const Eigen::Ref<const Points>& points, const Eigen::Ref<const Cells>& triangles) {
  require(triangles.cols() == 3, "vertex normals: cells need 3 vertices, got {}", triangles.cols());
  Points normals = Points::Zero(points.rows(), 3);
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
    const Eigen::Vector3d a = points.row(triangles(f, 0)), b = points.row(triangles(f, 1)),
                          c = points.row(triangles(f, 2));
    const Eigen::RowVector3d n = (b - a).cross(c - a).transpose();  // length = 2 × area: area weighting
    for (int k = 0; k < 3; ++k) normals.row(triangles(f, k)) += n;
  }
  for (Eigen::Index v = 0; v < normals.rows(); ++v) {
    const double length = normals.row(v).norm();
    if (length > 0.0) normals.row(v) /= length;
  }
  return normals;
}

Points read_points(const std::filesystem::path& path) {
  auto data = read_any(path);
  Points out(data->GetNumberOfPoints(), 3);
  for (vtkIdType i = 0; i < data->GetNumberOfPoints(); ++i) {
    double p[3];
    data->GetPoint(i, p);
    out.row(i) << p[0], p[1], p[2];
  }
  return out;
}

std::vector<std::string> read_point_array_names(const std::filesystem::path& path) {
  auto data = read_any(path);
  std::vector<std::string> names;
  for (int i = 0; i < data->GetPointData()->GetNumberOfArrays(); ++i)
    names.emplace_back(data->GetPointData()->GetArrayName(i));
  return names;
}

namespace {

/// The tuples of a numeric array as rows; `kind` names the attribute set in the error ("point-data", …).
Eigen::MatrixXd array_matrix(vtkDataArray* array, const std::filesystem::path& path, const char* kind,
                             const std::string& name) {
  require(array != nullptr, "{}: no {} array '{}'", path.string(), kind, name);
  Eigen::MatrixXd out(array->GetNumberOfTuples(), array->GetNumberOfComponents());
  for (vtkIdType r = 0; r < array->GetNumberOfTuples(); ++r)
    for (int c = 0; c < array->GetNumberOfComponents(); ++c) out(r, c) = array->GetComponent(r, c);
  return out;
}

}  // namespace

Eigen::MatrixXd read_point_array(const std::filesystem::path& path, const std::string& name) {
  return array_matrix(read_any(path)->GetPointData()->GetArray(name.c_str()), path, "point-data", name);
}

std::vector<std::string> read_cell_array_names(const std::filesystem::path& path) {
  auto data = read_any(path);
  std::vector<std::string> names;
  for (int i = 0; i < data->GetCellData()->GetNumberOfArrays(); ++i)
    names.emplace_back(data->GetCellData()->GetArrayName(i));
  return names;
}

Eigen::MatrixXd read_cell_array(const std::filesystem::path& path, const std::string& name) {
  return array_matrix(read_any(path)->GetCellData()->GetArray(name.c_str()), path, "cell-data", name);
}

Eigen::MatrixXd read_field_array(const std::filesystem::path& path, const std::string& name) {
  return array_matrix(read_any(path)->GetFieldData()->GetArray(name.c_str()), path, "field-data", name);
}

std::vector<std::string> read_field_array_names(const std::filesystem::path& path) {
  auto data = read_any(path);
  std::vector<std::string> names;
  for (int i = 0; i < data->GetFieldData()->GetNumberOfArrays(); ++i)
    if (const char* name = data->GetFieldData()->GetAbstractArray(i)->GetName()) names.emplace_back(name);
  return names;
}

std::vector<std::string> read_field_strings(const std::filesystem::path& path, const std::string& name) {
  auto data = read_any(path);
  vtkAbstractArray* array = data->GetFieldData()->GetAbstractArray(name.c_str());
  std::vector<std::string> out;
  if (auto* text = vtkUnsignedCharArray::SafeDownCast(array)) {  // UTF-8 text, one line per value
    const unsigned char* bytes = text->GetPointer(0);
    const std::string all(bytes, bytes + text->GetNumberOfValues());
    std::size_t start = 0;
    while (!all.empty()) {
      const std::size_t end = all.find('\n', start);
      out.push_back(all.substr(start, end == std::string::npos ? std::string::npos : end - start));
      if (end == std::string::npos) break;
      start = end + 1;
    }
    return out;
  }
  auto* strings = vtkStringArray::SafeDownCast(array);  // older sflsh files: a string array
  require(strings != nullptr, "{}: no field-data text array '{}'", path.string(), name);
  for (vtkIdType k = 0; k < strings->GetNumberOfValues(); ++k) out.push_back(strings->GetValue(k));
  return out;
}

Cells read_cells(const std::filesystem::path& path) {
  auto data = read_any(path);
  const vtkIdType n = data->GetNumberOfCells();
  vtkNew<vtkIdList> ids;
  if (n > 0) data->GetCellPoints(0, ids);
  Cells out(n, n > 0 ? ids->GetNumberOfIds() : 3);
  for (vtkIdType c = 0; c < n; ++c) {
    data->GetCellPoints(c, ids);
    require(ids->GetNumberOfIds() == out.cols(), "{}: cells of different sizes", path.string());
    for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k) out(c, k) = static_cast<int>(ids->GetId(k));
  }
  return out;
}

}  // namespace sflsh::vtk
