// curves.png: the material curves drawn with VTK's 2-D charts (vtkChartXY in a vtkContextView), offscreen.
#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/virtual_display.hpp>
#include <sflsh/core/window_png.hpp>
#include <sflsh/material/curves.hpp>

#include <vtkAxis.h>
#include <vtkChartLegend.h>
#include <vtkChartXY.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPen.h>
#include <vtkPlot.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkTable.h>
#include <vtkTextProperty.h>

#include <array>
#include <cstdlib>

namespace sflsh::material {

namespace {

vtkSmartPointer<vtkTable> table_of(const MaterialCurve& curve) {
  auto table = vtkSmartPointer<vtkTable>::New();
  vtkNew<vtkDoubleArray> strain;
  strain->SetName("strain");
  vtkNew<vtkDoubleArray> stress;
  stress->SetName(std::string(curve_test_name(curve.test)).c_str());
  table->AddColumn(strain);
  table->AddColumn(stress);
  table->SetNumberOfRows(static_cast<vtkIdType>(curve.points.size()));
  for (std::size_t i = 0; i < curve.points.size(); ++i) {
    table->SetValue(static_cast<vtkIdType>(i), 0, curve.points[i].strain);
    table->SetValue(static_cast<vtkIdType>(i), 1, curve.points[i].stress * 1e-3);  // kPa
  }
  return table;
}

}  // namespace

void plot_curves_png(const std::filesystem::path& path, const std::vector<MaterialCurve>& curves,
                     const std::string& title) {
  require_display("plot");  // $DISPLAY, or a virtual display started for this process
  require(!curves.empty(), "plot: no curves to draw");

  vtkNew<vtkContextView> view;
  view->GetRenderer()->SetBackground(1.0, 1.0, 1.0);
  view->GetRenderWindow()->SetOffScreenRendering(1);
  view->GetRenderWindow()->SetSize(900, 600);
  vtkNew<vtkChartXY> chart;
  view->GetScene()->AddItem(chart);
  chart->SetTitle(title);
  chart->GetTitleProperties()->SetFontSize(16);
  chart->SetShowLegend(true);
  chart->GetLegend()->SetHorizontalAlignment(vtkChartLegend::LEFT);
  chart->GetLegend()->SetVerticalAlignment(vtkChartLegend::TOP);
  chart->GetAxis(vtkAxis::BOTTOM)->SetTitle("strain (stretch - 1; shear: gamma)");
  chart->GetAxis(vtkAxis::LEFT)->SetTitle("Cauchy stress [kPa]");

  const std::array<std::array<unsigned char, 3>, 3> colors = {{{200, 60, 40}, {40, 90, 200}, {40, 150, 60}}};
  std::vector<vtkSmartPointer<vtkTable>> tables;  // the plots reference their tables until rendering
  for (std::size_t c = 0; c < curves.size(); ++c) {
    tables.push_back(table_of(curves[c]));
    vtkPlot* line = chart->AddPlot(vtkChart::LINE);
    line->SetInputData(tables.back(), 0, 1);
    const auto& rgb = colors[c % colors.size()];
    line->SetColor(rgb[0], rgb[1], rgb[2], 255);
    line->SetWidth(2.5);
    line->SetLabel(std::string(curve_test_name(curves[c].test)));
  }

  view->Render();
  write_window_png(*view->GetRenderWindow(), path);
}

}  // namespace sflsh::material
