# The Python module `sflsh` (python/, docs/python.md): pybind11 and NumPy from Debian (scripts/setup.sh).
# Debian's interpreter is preferred over any other python3 earlier in PATH (a pyenv shim, a venv), because the
# module is built against Debian's pybind11 and imported beside Debian's NumPy; pass -DPython3_EXECUTABLE=… to
# choose another one. SFLSH_PYTHON defaults to ON when Python with NumPy, pybind11 and pybind11_json are found.
if(NOT DEFINED Python3_EXECUTABLE AND EXISTS /usr/bin/python3)
  set(Python3_EXECUTABLE /usr/bin/python3 CACHE FILEPATH "Python interpreter the sflsh module is built for")
endif()
find_package(Python3 COMPONENTS Interpreter Development.Module NumPy)
if(Python3_FOUND)
  find_package(pybind11 2.6 CONFIG QUIET)   # after Python3: pybind11 then uses this interpreter (FindPython mode)
  find_package(pybind11_json 0.2 CONFIG QUIET)   # nlohmann::json ↔ Python objects (summaries)
endif()
if(Python3_FOUND AND Python3_NumPy_FOUND AND pybind11_FOUND AND pybind11_json_FOUND)
  set(SFLSH_PYTHON_AVAILABLE ON)
else()
  set(SFLSH_PYTHON_AVAILABLE OFF)
endif()
option(SFLSH_PYTHON "Build the Python module sflsh (pybind11; needs position-independent libraries)" ${SFLSH_PYTHON_AVAILABLE})
if(SFLSH_PYTHON AND NOT SFLSH_PYTHON_AVAILABLE)
  message(FATAL_ERROR "SFLSH_PYTHON is ON but Python 3 with NumPy and pybind11 was not found "
                      "(Debian: python3-dev python3-numpy pybind11-dev python3-pybind11 pybind11-json-dev; scripts/setup.sh)")
endif()
set(SFLSH_PYTHON_INSTALL_DIR "lib/python3/dist-packages" CACHE STRING
    "Where `cmake --install` puts the sflsh module, relative to the prefix")
