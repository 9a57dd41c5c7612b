# The Python package (python/): on when pybind11 (pybind11-dev) and Python 3
# with its headers (python3-dev) and NumPy (python3-numpy) are found.
#
# Debian's /usr/bin/python3 is the interpreter python3-numpy and
# python3-pytest belong to; a python3 earlier on PATH (pyenv, conda) usually
# lacks them, so Debian's is preferred unless -DPython3_EXECUTABLE names another.
if(NOT DEFINED Python3_EXECUTABLE AND EXISTS /usr/bin/python3)
  set(Python3_EXECUTABLE /usr/bin/python3)
endif()
find_package(Python3 COMPONENTS Interpreter Development.Module NumPy QUIET)
# After Python3: pybind11 2.10 then builds with CMake's FindPython, as found above.
find_package(pybind11 2.10 CONFIG QUIET)
cmake_dependent_option(SCAN2LOD_WITH_PYTHON "Build the Python package into build/python" ON
                       "pybind11_FOUND;Python3_FOUND;Python3_NumPy_FOUND" OFF)
message(STATUS "scan2lod: Python ${SCAN2LOD_WITH_PYTHON}")
if(SCAN2LOD_WITH_PYTHON)
  add_subdirectory(python)
endif()
