# Every dependency comes from Debian 12 packages (scripts/setup.sh); nothing is downloaded.
# Versions pinned by what bookworm ships: PETSc 3.18, SUNDIALS 6.4, CGAL 5.5, gmsh 4.8, VTK 9.1, HDF5 1.10.
if(TARGET sflsh::deps_done)
  return()
endif()

# MPI first: PETSc.pc carries no MPI include path and SUNDIALS' targets reference MPI::MPI_C.
find_package(MPI REQUIRED COMPONENTS C CXX)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(PkgConfig REQUIRED)
# Pin the real-double 32-bit-index PETSc build (the .pc is an alternatives link).
set(ENV{PKG_CONFIG_PATH} "/usr/lib/petscdir/petsc3.18/x86_64-linux-gnu-real/lib/pkgconfig:$ENV{PKG_CONFIG_PATH}")
pkg_check_modules(PETSC REQUIRED IMPORTED_TARGET PETSc)
find_package(SUNDIALS 6 REQUIRED CONFIG)
set(CGAL_DO_NOT_WARN_ABOUT_CMAKE_BUILD_TYPE TRUE)
find_package(CGAL REQUIRED)

find_path(GMSH_INCLUDE_DIR gmsh.h REQUIRED)
find_library(GMSH_LIBRARY NAMES gmsh REQUIRED)
if(NOT TARGET gmsh::gmsh)
  add_library(gmsh::gmsh UNKNOWN IMPORTED)
  set_target_properties(gmsh::gmsh PROPERTIES
    IMPORTED_LOCATION "${GMSH_LIBRARY}" INTERFACE_INCLUDE_DIRECTORIES "${GMSH_INCLUDE_DIR}")
endif()

# VTK from Debian's libvtk9-dev (9.1), or, on a machine with ParaView's Python (python3-paraview conflicts with
# libvtk9-dev's python3-vtk9), the VTK 9.2 that paraview-dev installs under cmake/paraview-5.11/vtk
# (docs/build.md, "ParaView on the same machine"). The PATHS are searched after the default locations, so
# libvtk9-dev wins when both are present.
set(SFLSH_VTK_COMPONENTS
  CommonCore CommonDataModel CommonExecutionModel IOXML IOLegacy FiltersGeometry
  RenderingCore RenderingOpenGL2 InteractionStyle RenderingFreeType IOImage)
file(GLOB SFLSH_PARAVIEW_VTK_DIRS /usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/cmake/paraview-*/vtk)
find_package(VTK 9 COMPONENTS ${SFLSH_VTK_COMPONENTS} PATHS ${SFLSH_PARAVIEW_VTK_DIRS})
if(NOT VTK_FOUND)
  message(FATAL_ERROR "VTK 9 not found: install Debian's libvtk9-dev (scripts/setup.sh), or paraview-dev on a "
                      "machine with python3-paraview (SFLSH_PARAVIEW=1 scripts/setup.sh)")
endif()
message(STATUS "VTK ${VTK_VERSION} from ${VTK_DIR}")
# The mesh-file readers of the scene stage (.obj/.stl: IOGeometry, .ply: IOPLY) are linked by sflsh_scene
# only, and the pictures' colour bar (RenderingAnnotation: vtkScalarBarActor) by sflsh_core: found here, at the
# top level, so that their own dependencies (JsonCpp) are visible to every directory, but kept out of
# VTK_LIBRARIES so that the other targets' link and compile lines do not change.
set(SFLSH_VTK_LIBRARIES_CORE ${VTK_LIBRARIES})
find_package(VTK 9 REQUIRED COMPONENTS IOGeometry IOPLY FiltersCore RenderingAnnotation)
set(VTK_LIBRARIES ${SFLSH_VTK_LIBRARIES_CORE})
find_package(HDF5 REQUIRED COMPONENTS C CXX)   # serial flavour: /usr/include/hdf5/serial

find_package(CLI11 2 REQUIRED CONFIG)
find_package(nlohmann_json 3.11 REQUIRED CONFIG)
find_package(tomlplusplus 3 REQUIRED CONFIG)
find_package(fmt 9 REQUIRED CONFIG)
find_package(spdlog 1.10 REQUIRED CONFIG)
pkg_check_modules(LIBZIP REQUIRED IMPORTED_TARGET libzip)  # libzip's CMake config is broken on bookworm
find_package(ZLIB REQUIRED)
find_package(TBB REQUIRED CONFIG)
find_package(OpenMP REQUIRED COMPONENTS CXX)
find_package(muparser 2 REQUIRED CONFIG)           # muparser::muparser (expressions in verify problems)

add_library(sflsh_deps_done INTERFACE)
add_library(sflsh::deps_done ALIAS sflsh_deps_done)
