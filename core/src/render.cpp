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
#include <limits>

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

/// The lookup table (blue to red) over [lo, hi] of the surfaces' scalars, or over view.scalar_range.
vtkSmartPointer<vtkLookupTable> make_lookup_table(const std::vector<const Surface*>& surfaces, const View& view,
                                                  double& lo, double& hi) {
  lo = 0.0;
  hi = 1.0;
  if (view.scalar_range) {
    lo = view.scalar_range->first;
    hi = view.scalar_range->second;
  } else {
    bool first = true;
    for (const Surface* s : surfaces)
      if (s->scalars && s->scalars->size() > 0) {
        lo = first ? s->scalars->minCoeff() : std::min(lo, s->scalars->minCoeff());
        hi = first ? s->scalars->maxCoeff() : std::max(hi, s->scalars->maxCoeff());
        first = false;
      }
  }
  if (!(hi > lo)) hi = lo + 1.0;
  auto lut = vtkSmartPointer<vtkLookupTable>::New();
  lut->SetHueRange(0.667, 0.0);
  lut->SetTableRange(lo, hi);
  lut->Build();
  return lut;
}

void add_surfaces(vtkRenderer* renderer, const std::vector<Surface>& surfaces, vtkLookupTable* lut, double lo,
                  double hi) {
  for (const Surface& s : surfaces) {
    vtkNew<vtkPolyDataNormals> normals;
    normals->SetInputData(to_polydata(s));
    normals->SplittingOff();
    normals->ConsistencyOff();
    vtkNew<vtkPolyDataMapper> mapper;
    mapper->SetInputConnection(normals->GetOutputPort());
    if (s.scalars) {
      mapper->SetLookupTable(lut);
      mapper->SetScalarRange(lo, hi);
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
}

void add_text(vtkRenderer* renderer, const std::string& text, int x, int y, int size) {
  vtkNew<vtkTextActor> actor;
  actor->SetInput(text.c_str());
  actor->GetTextProperty()->SetFontSize(size);
  actor->GetTextProperty()->SetColor(0.1, 0.1, 0.1);
  actor->SetDisplayPosition(x, y);
  renderer->AddActor2D(actor);
}

/// Points the camera along the named view at the box b (xmin, xmax, ymin, ymax, zmin, zmax), orthographic, the
/// box filling a picture of the aspect ratio (width / height).
void frame_camera(vtkRenderer* renderer, const std::string& name, double b[6], double aspect) {
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetFocalPoint(0, 0, 0);
  camera->SetViewUp(0, 1, 0);
  if (name == "front")
    camera->SetPosition(0, 0, 10);
  else if (name == "back")
    camera->SetPosition(0, 0, -10);
  else if (name == "side")
    camera->SetPosition(10, 0, 0);
  else if (name == "three_quarter")
    camera->SetPosition(6, 2, 8);
  else if (name == "top") {
    camera->SetPosition(0, 10, 0);
    camera->SetViewUp(0, 0, -1);
  } else {
    throw_error("render: unknown view '{}' (front, back, side, three_quarter, top)", name);
  }
  // Orthographic framing that fills the picture: half the visible extent along the view-up axis,
  // or along the horizontal axis scaled by the aspect ratio, whichever is larger.
  camera->ParallelProjectionOn();
  renderer->ResetCamera(b);
  const double extent_x = b[1] - b[0], extent_y = b[3] - b[2], extent_z = b[5] - b[4];
  double vertical = extent_y, horizontal = extent_x;
  if (name == "side") horizontal = extent_z;
  if (name == "top") vertical = extent_z;
  if (name == "three_quarter") horizontal = std::hypot(extent_x, extent_z);
  camera->SetParallelScale(0.53 * std::max(vertical, horizontal / aspect));
  renderer->ResetCameraClippingRange();
}

void write_window_png(const std::filesystem::path& path, vtkRenderWindow* window) {
  window->SetOffScreenRendering(1);
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

/// The box of the surfaces' points (offsets applied).
void surface_bounds(const std::vector<const Surface*>& surfaces, double b[6]) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Surface* s : surfaces)
    for (Eigen::Index i = 0; i < s->points.rows(); ++i) {
      const Eigen::Vector3d p = s->points.row(i).transpose() + s->offset;
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  for (int k = 0; k < 3; ++k) {
    b[2 * k] = lo(k);
    b[2 * k + 1] = hi(k);
  }
}

}  // namespace

void render_png(const std::filesystem::path& path, const std::vector<Surface>& surfaces, const View& view) {
  require_display("render");  // $DISPLAY, or a virtual display started for this process
  require(!surfaces.empty(), "render: nothing to draw");

  vtkNew<vtkRenderer> renderer;
  renderer->SetBackground(1.0, 1.0, 1.0);
  std::vector<const Surface*> all;
  for (const Surface& s : surfaces) all.push_back(&s);
  double lo = 0.0, hi = 1.0;
  const auto lut = make_lookup_table(all, view, lo, hi);
  add_surfaces(renderer, surfaces, lut, lo, hi);
  if (!view.title.empty()) add_text(renderer, view.title, 10, view.height - 34, 20);
  double b[6];
  surface_bounds(all, b);
  frame_camera(renderer, view.name, b, static_cast<double>(view.width) / view.height);

  vtkNew<vtkRenderWindow> window;
  window->AddRenderer(renderer);
  window->SetSize(view.width, view.height);
  write_window_png(path, window);
}

void render_strip_png(const std::filesystem::path& path, const std::vector<Panel>& panels, const View& view) {
  require_display("render");
  require(!panels.empty(), "render: no panels to draw");
  // One colour scale and one camera for every panel: the panels compare like with like.
  std::vector<const Surface*> all, framed;
  for (const Panel& p : panels)
    for (const Surface& s : p.surfaces) {
      all.push_back(&s);
      if (s.framed) framed.push_back(&s);
    }
  require(!all.empty(), "render: nothing to draw");
  if (framed.empty()) framed = all;
  double lo = 0.0, hi = 1.0;
  const auto lut = make_lookup_table(all, view, lo, hi);
  double b[6];
  surface_bounds(framed, b);
  const int title_height = view.title.empty() ? 0 : 40;
  const int caption_height = 36;
  const int panel_height = view.height - title_height - caption_height;
  require(panel_height > 16, "render: a strip panel of height {} px leaves no room for the picture", view.height);
  const auto n = static_cast<double>(panels.size());
  const int width = view.width * static_cast<int>(panels.size());
  vtkNew<vtkRenderWindow> window;
  window->SetSize(width, view.height);
  // A white background renderer under the panels holds the title and the captions.
  vtkNew<vtkRenderer> back;
  back->SetBackground(1.0, 1.0, 1.0);
  back->SetViewport(0.0, 0.0, 1.0, 1.0);
  back->SetLayer(0);
  if (!view.title.empty()) add_text(back, view.title, 10, view.height - 30, 20);
  for (std::size_t i = 0; i < panels.size(); ++i)
    add_text(back, panels[i].caption, static_cast<int>(i) * view.width + view.width / 2 - 50, 8, 18);
  window->SetNumberOfLayers(2);
  window->AddRenderer(back);
  const double y0 = static_cast<double>(caption_height) / view.height;
  const double y1 = 1.0 - static_cast<double>(title_height) / view.height;
  for (std::size_t i = 0; i < panels.size(); ++i) {
    vtkNew<vtkRenderer> renderer;
    renderer->SetLayer(1);
    renderer->SetViewport(static_cast<double>(i) / n, y0, static_cast<double>(i + 1) / n, y1);
    add_surfaces(renderer, panels[i].surfaces, lut, lo, hi);
    frame_camera(renderer, view.name, b, static_cast<double>(view.width) / panel_height);
    window->AddRenderer(renderer);
  }
  write_window_png(path, window);
}

}  // namespace sflsh::render
