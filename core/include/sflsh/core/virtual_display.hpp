#pragma once
// An X display for pictures on machines without one. Debian's VTK renders offscreen through X (GLX), so a
// picture needs a display even when nothing is shown. require_display() uses $DISPLAY when it is set; on a
// headless machine (a cluster node, CI) it starts a virtual display (Xvfb, Debian package `xvfb`, which
// scripts/setup.sh installs), sets $DISPLAY for this process, and stops the display when the process ends.
// No flag and no `xvfb-run` are needed.
#include <string_view>

namespace sflsh {

/// Makes sure VTK can render: returns when $DISPLAY is usable, starting Xvfb once per process when it is
/// not set. Throws sflsh::Error "<what>: …" naming what to install when no display can be had.
void require_display(std::string_view what);

}  // namespace sflsh
