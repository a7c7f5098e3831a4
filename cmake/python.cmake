# The interpreter the Python module is built for: Debian's /usr/bin/python3 (with python3-numpy),
# not whatever python3 comes first on PATH; -DPython3_EXECUTABLE=... chooses another.
if(NOT Python3_EXECUTABLE AND EXISTS /usr/bin/python3)
  set(Python3_EXECUTABLE /usr/bin/python3 CACHE FILEPATH "The Python the ctk module is built for")
endif()
find_package(Python3 QUIET COMPONENTS Interpreter Development.Module NumPy)
if(NOT Python3_FOUND OR NOT Python3_NumPy_FOUND)
  ctk_missing("Python 3 with its headers and numpy (${Python3_EXECUTABLE})" "python3-dev python3-numpy")
endif()
ctk_find_package(pybind11 pybind11-dev CONFIG)
# The libraries are linked into a shared module.
set(CMAKE_POSITION_INDEPENDENT_CODE ON)
