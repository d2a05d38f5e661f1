#include <sflsh/core/error.hpp>
#include <sflsh/core/vtk_surface_reader.hpp>
#include <vtkCellArray.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkXMLPolyDataReader.h>

namespace sflsh::vtk {

SurfaceFrame read_surface_frame(const std::filesystem::path& path) {
  require(std::filesystem::is_regular_file(path), "{}: not a file, expected a .vtp surface", path.string());
  vtkNew<vtkXMLPolyDataReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkPolyData* poly = reader->GetOutput();
  require(poly != nullptr && poly->GetPoints() != nullptr && poly->GetNumberOfPoints() > 0,
          "{}: no points, expected a .vtp surface", path.string());
  SurfaceFrame frame;
  frame.points.resize(poly->GetNumberOfPoints(), 3);
  for (vtkIdType i = 0; i < poly->GetNumberOfPoints(); ++i) {
    double p[3];
    poly->GetPoint(i, p);
    frame.points.row(i) << p[0], p[1], p[2];
  }
  vtkCellArray* polys = poly->GetPolys();
  require(polys != nullptr && polys->GetNumberOfCells() > 0, "{}: no triangles, expected a surface", path.string());
  frame.triangles.resize(polys->GetNumberOfCells(), 3);
  vtkNew<vtkIdList> ids;
  polys->InitTraversal();
  for (vtkIdType c = 0; polys->GetNextCell(ids); ++c) {
    require(ids->GetNumberOfIds() == 3, "{}: cell {} has {} points, expected triangles", path.string(), c,
            ids->GetNumberOfIds());
    for (int k = 0; k < 3; ++k) frame.triangles(c, k) = static_cast<int>(ids->GetId(k));
  }
  vtkDataArray* t = poly->GetFieldData() ? poly->GetFieldData()->GetArray("TimeValue") : nullptr;
  frame.time = t != nullptr && t->GetNumberOfTuples() > 0 ? t->GetComponent(0, 0) : 0.0;
  return frame;
}

}  // namespace sflsh::vtk
