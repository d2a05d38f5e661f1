#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/colormap.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/render.hpp>
#include <sflsh/core/virtual_display.hpp>
#include <sflsh/core/window_png.hpp>

#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkCoordinate.h>
#include <vtkDoubleArray.h>
#include <vtkLight.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkPolyDataNormals.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>

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

/// The lookup table of view.colormap (256 colours) over [lo, hi] of the surfaces' scalars, or over
/// view.scalar_range.
vtkSmartPointer<vtkLookupTable> make_lookup_table(const std::vector<const Surface*>& surfaces, const View& view,
                                                  double& lo, double& hi) {
  check_colormap(view.colormap, "render: colour map");
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
  constexpr int kColors = 256;
  lut->SetNumberOfTableValues(kColors);
  for (int k = 0; k < kColors; ++k) {
    const std::array<double, 3> c = colormap_color(view.colormap, k / static_cast<double>(kColors - 1));
    lut->SetTableValue(k, c[0], c[1], c[2], 1.0);
  }
  lut->SetTableRange(lo, hi);
  return lut;
}

bool any_scalars(const std::vector<const Surface*>& surfaces) {
  return std::any_of(surfaces.begin(), surfaces.end(), [](const Surface* s) { return s->scalars.has_value(); });
}

/// The colour bar of `lut` in the column [x0, x1] (normalized viewport of `renderer`) between heights y0 and y1:
/// the bar, its ticks and its title (the quantity and its unit).
void add_color_bar(vtkRenderer* renderer, vtkLookupTable* lut, const std::string& title, double x0, double x1,
                   double y0, double y1) {
  vtkNew<vtkScalarBarActor> bar;
  bar->SetLookupTable(lut);
  bar->SetMaximumNumberOfColors(256);
  bar->SetOrientationToVertical();
  bar->SetNumberOfLabels(5);
  bar->SetLabelFormat("%-#6.3g");
  bar->SetTitle(title.c_str());
  bar->UnconstrainedFontSizeOn();
  bar->SetBarRatio(0.28);
  bar->SetTextPad(4);
  bar->SetVerticalTitleSeparation(10);
  for (vtkTextProperty* text : {bar->GetTitleTextProperty(), bar->GetLabelTextProperty()}) {
    text->SetColor(0.1, 0.1, 0.1);
    text->SetFontSize(16);
    text->ShadowOff();
    text->ItalicOff();
    text->BoldOff();
  }
  bar->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
  bar->GetPositionCoordinate()->SetValue(x0, y0);
  bar->SetWidth(x1 - x0);
  bar->SetHeight(y1 - y0);
  renderer->AddActor2D(bar);
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

void render_window_png(const std::filesystem::path& path, vtkRenderWindow* window) {
  window->SetOffScreenRendering(1);
  window->SetMultiSamples(4);
  window->Render();
  write_window_png(*window, path);
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

/// Draws the panels side by side into the window: a white background renderer holds the title, the captions and
/// the colour bar (in its column right of the panels); each panel has its renderer over the same camera box.
void draw(const std::filesystem::path& path, const std::vector<Panel>& panels, const View& view, int window_width,
          int panel_width, int caption_height) {
  std::vector<const Surface*> all, framed;
  for (const Panel& p : panels)
    for (const Surface& s : p.surfaces) {
      all.push_back(&s);
      if (s.framed) framed.push_back(&s);
    }
  require(!all.empty(), "render: nothing to draw");
  if (framed.empty()) framed = all;
  // One colour scale and one camera for every panel: the panels compare like with like.
  double lo = 0.0, hi = 1.0;
  const auto lut = make_lookup_table(all, view, lo, hi);
  double b[6];
  surface_bounds(framed, b);
  const auto title_lines = static_cast<int>(std::count(view.title.begin(), view.title.end(), '\n')) + 1;
  // The title's font shrinks with a narrow picture (20 px at 900 px and wider, 12 px at most).
  const int title_font = std::clamp(window_width / 45, 12, 20);
  const int title_height = view.title.empty() ? 0 : 12 + (title_font + 6) * title_lines;
  const int panel_height = view.height - title_height - caption_height;
  require(panel_height > 16, "render: a picture of height {} px leaves no room for the surfaces", view.height);
  vtkNew<vtkRenderWindow> window;
  window->SetSize(window_width, view.height);
  vtkNew<vtkRenderer> back;
  back->SetBackground(1.0, 1.0, 1.0);
  back->SetViewport(0.0, 0.0, 1.0, 1.0);
  back->SetLayer(0);
  if (!view.title.empty()) add_text(back, view.title, 10, view.height - title_height + 8, title_font);
  const double width = window_width;
  for (std::size_t i = 0; i < panels.size(); ++i)
    if (!panels[i].caption.empty())
      add_text(back, panels[i].caption, static_cast<int>(i) * panel_width + panel_width / 2 - 50, 8, 18);
  const double y0 = static_cast<double>(caption_height) / view.height;
  const double y1 = 1.0 - static_cast<double>(title_height) / view.height;
  const double panels_right = static_cast<double>(panel_width) * static_cast<double>(panels.size()) / width;
  if (any_scalars(all))
    add_color_bar(back, lut, view.scalar_title, panels_right + 14.0 / width, 1.0 - 10.0 / width, y0 + 0.12 * (y1 - y0),
                  y0 + 0.82 * (y1 - y0));
  window->SetNumberOfLayers(2);
  window->AddRenderer(back);
  for (std::size_t i = 0; i < panels.size(); ++i) {
    vtkNew<vtkRenderer> renderer;
    renderer->SetLayer(1);
    renderer->SetViewport(static_cast<double>(i) * panel_width / width, y0,
                          static_cast<double>(i + 1) * panel_width / width, y1);
    add_surfaces(renderer, panels[i].surfaces, lut, lo, hi);
    frame_camera(renderer, view.name, b, static_cast<double>(panel_width) / panel_height);
    window->AddRenderer(renderer);
  }
  render_window_png(path, window);
}

}  // namespace

void render_png(const std::filesystem::path& path, const std::vector<Surface>& surfaces, const View& view) {
  require_display("render");  // $DISPLAY, or a virtual display started for this process
  require(!surfaces.empty(), "render: nothing to draw");
  Panel panel;
  panel.surfaces = surfaces;
  bool scalars = false;
  for (const Surface& s : surfaces) scalars = scalars || s.scalars.has_value();
  const int bar = scalars ? kColorBarWidth : 0;
  require(view.width > bar + 16, "render: a picture of width {} px leaves no room beside the colour bar", view.width);
  draw(path, {panel}, view, view.width, view.width - bar, 0);
}

void render_strip_png(const std::filesystem::path& path, const std::vector<Panel>& panels, const View& view) {
  require_display("render");
  require(!panels.empty(), "render: no panels to draw");
  bool scalars = false;
  for (const Panel& p : panels)
    for (const Surface& s : p.surfaces) scalars = scalars || s.scalars.has_value();
  const int width = view.width * static_cast<int>(panels.size()) + (scalars ? kColorBarWidth : 0);
  draw(path, panels, view, width, view.width, 36);
}

}  // namespace sflsh::render
