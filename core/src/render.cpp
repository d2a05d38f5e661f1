#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/render.hpp>
#include <sflsh/core/virtual_display.hpp>

#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkLight.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkPolyDataNormals.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace sflsh::render {

namespace {

vtkSmartPointer<vtkPolyData> to_polydata(const Surface& s) {
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkPoints> points;
  points->SetNumberOfPoints(s.points.rows());
  for (Eigen::Index i = 0; i < s.points.rows(); ++i) {
    const Eigen::Vector3d p = s.points.row(i).transpose() + s.offset;
    points->SetPoint(i, p.x(), p.y(), p.z());
  }
  vtkNew<vtkCellArray> cells;
  for (Eigen::Index f = 0; f < s.triangles.rows(); ++f) {
    const vtkIdType ids[3] = {s.triangles(f, 0), s.triangles(f, 1), s.triangles(f, 2)};
    cells->InsertNextCell(3, ids);
  }
  poly->SetPoints(points);
  poly->SetPolys(cells);
  if (s.scalars) {
    require(s.scalars->size() == s.points.rows(), "render: {} scalars for {} points", s.scalars->size(),
            s.points.rows());
    vtkNew<vtkDoubleArray> values;
    values->SetName("scalars");
    values->SetNumberOfTuples(s.scalars->size());
    for (Eigen::Index i = 0; i < s.scalars->size(); ++i) values->SetValue(i, (*s.scalars)(i));
    poly->GetPointData()->SetScalars(values);
  }
  return poly;
}

}  // namespace

void render_png(const std::filesystem::path& path, const std::vector<Surface>& surfaces, const View& view) {
  require_display("render");  // $DISPLAY, or a virtual display started for this process
  require(!surfaces.empty(), "render: nothing to draw");

  vtkNew<vtkRenderer> renderer;
  renderer->SetBackground(1.0, 1.0, 1.0);
  double lo = 0.0, hi = 1.0;
  if (view.scalar_range) {
    lo = view.scalar_range->first;
    hi = view.scalar_range->second;
  } else {
    bool first = true;
    for (const Surface& s : surfaces)
      if (s.scalars && s.scalars->size() > 0) {
        lo = first ? s.scalars->minCoeff() : std::min(lo, s.scalars->minCoeff());
        hi = first ? s.scalars->maxCoeff() : std::max(hi, s.scalars->maxCoeff());
        first = false;
      }
  }
  vtkNew<vtkLookupTable> lut;
  lut->SetHueRange(0.667, 0.0);
  lut->SetTableRange(lo, hi > lo ? hi : lo + 1.0);
  lut->Build();

  for (const Surface& s : surfaces) {
    vtkNew<vtkPolyDataNormals> normals;
    normals->SetInputData(to_polydata(s));
    normals->SplittingOff();
    normals->ConsistencyOff();
    vtkNew<vtkPolyDataMapper> mapper;
    mapper->SetInputConnection(normals->GetOutputPort());
    if (s.scalars) {
      mapper->SetLookupTable(lut);
      mapper->SetScalarRange(lo, hi > lo ? hi : lo + 1.0);
      mapper->ScalarVisibilityOn();
    } else {
      mapper->ScalarVisibilityOff();
    }
    vtkNew<vtkActor> actor;
    actor->SetMapper(mapper);
    actor->GetProperty()->SetColor(s.color[0], s.color[1], s.color[2]);
    actor->GetProperty()->SetSpecular(0.15);
    actor->GetProperty()->SetSpecularPower(20.0);
    renderer->AddActor(actor);
  }

  if (!view.title.empty()) {
    vtkNew<vtkTextActor> text;
    text->SetInput(view.title.c_str());
    text->GetTextProperty()->SetFontSize(20);
    text->GetTextProperty()->SetColor(0.1, 0.1, 0.1);
    text->SetDisplayPosition(10, view.height - 34);
    renderer->AddActor2D(text);
  }

  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetFocalPoint(0, 0, 0);
  camera->SetViewUp(0, 1, 0);
  if (view.name == "front")
    camera->SetPosition(0, 0, 10);
  else if (view.name == "back")
    camera->SetPosition(0, 0, -10);
  else if (view.name == "side")
    camera->SetPosition(10, 0, 0);
  else if (view.name == "three_quarter")
    camera->SetPosition(6, 2, 8);
  else if (view.name == "top") {
    camera->SetPosition(0, 10, 0);
    camera->SetViewUp(0, 0, -1);
  } else {
    throw_error("render: unknown view '{}' (front, back, side, three_quarter, top)", view.name);
  }
  // Orthographic framing that fills the picture: half the visible extent along the view-up axis,
  // or along the horizontal axis scaled by the aspect ratio, whichever is larger.
  camera->ParallelProjectionOn();
  renderer->ResetCamera();
  double b[6];
  renderer->ComputeVisiblePropBounds(b);
  const double extent_x = b[1] - b[0], extent_y = b[3] - b[2], extent_z = b[5] - b[4];
  const double aspect = static_cast<double>(view.width) / view.height;
  double vertical = extent_y, horizontal = extent_x;
  if (view.name == "side") horizontal = extent_z;
  if (view.name == "top") vertical = extent_z;
  if (view.name == "three_quarter") horizontal = std::hypot(extent_x, extent_z);
  camera->SetParallelScale(0.53 * std::max(vertical, horizontal / aspect));
  renderer->ResetCameraClippingRange();

  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->AddRenderer(renderer);
  window->SetSize(view.width, view.height);
  window->SetMultiSamples(4);
  window->Render();

  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->ReadFrontBufferOff();
  grab->Update();
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    vtkNew<vtkPNGWriter> writer;
    writer->SetFileName(tmp.c_str());
    writer->SetInputConnection(grab->GetOutputPort());
    writer->Write();
  });
}

}  // namespace sflsh::render
