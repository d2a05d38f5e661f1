#pragma once
// A VTK render window to a PNG file: the one place the project grabs a rendered image (body renders, charts, the
// material's curves) and writes it, encoded in memory and then written with checked writes so that a full disk is an
// error naming the file (docs/output.md).
#include <filesystem>

class vtkRenderWindow;

namespace sflsh {

/// Grabs what `window` shows (render it first) and writes it to `path` as a PNG, atomically. Throws sflsh::Error naming
/// the file when encoding or writing fails.
void write_window_png(vtkRenderWindow& window, const std::filesystem::path& path);

}  // namespace sflsh
