// A render window to a PNG file (window_png.hpp).
#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/window_png.hpp>

#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkRenderWindow.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>

#include <string_view>

namespace sflsh {

void write_window_png(vtkRenderWindow& window, const std::filesystem::path& path) {
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(&window);
  grab->ReadFrontBufferOff();
  grab->Update();
  // Into memory, then to the file with checked writes, so a full disk is an error naming the file (issue 45).
  vtkNew<vtkPNGWriter> writer;
  writer->WriteToMemoryOn();
  writer->SetInputConnection(grab->GetOutputPort());
  writer->Write();
  vtkUnsignedCharArray* png = writer->GetResult();
  require(writer->GetErrorCode() == 0 && png != nullptr && png->GetNumberOfValues() > 0, "{}: PNG encoding failed",
          path.string());
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    write_file_checked(tmp, path,
                       std::string_view(reinterpret_cast<const char*>(png->GetPointer(0)),
                                        static_cast<std::size_t>(png->GetNumberOfValues())));
  });
}

}  // namespace sflsh
