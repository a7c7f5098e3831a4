# Finds every third-party dependency and fails early, naming the Debian package that provides it.
# scripts/setup.sh installs all of them.

function(ctk_missing what package)
  message(FATAL_ERROR
    "ctk: ${what} not found. Install the Debian package '${package}' "
    "(or run scripts/setup.sh, which installs everything ctk needs).")
endfunction()

macro(ctk_find_package name package)
  find_package(${name} ${ARGN} QUIET)
  if(NOT ${name}_FOUND)
    ctk_missing(${name} ${package})
  endif()
endmacro()

ctk_find_package(Eigen3 libeigen3-dev NO_MODULE)
ctk_find_package(Ceres libceres-dev)
ctk_find_package(OpenCV libopencv-dev COMPONENTS core imgproc)
ctk_find_package(OpenImageIO libopenimageio-dev)
ctk_find_package(OpenEXR libopenexr-dev)
ctk_find_package(TIFF libtiff-dev)
ctk_find_package(nlohmann_json nlohmann-json3-dev)
ctk_find_package(CLI11 libcli11-dev)
ctk_find_package(pugixml libpugixml-dev)
ctk_find_package(OpenMP libgomp1 COMPONENTS CXX)
ctk_find_package(hwy libhwy-dev)
ctk_find_package(PkgConfig pkg-config)

pkg_check_modules(HEALPIX QUIET IMPORTED_TARGET healpix_cxx)
if(NOT HEALPIX_FOUND)
  ctk_missing("HEALPix C++ (healpix_cxx)" libhealpix-cxx-dev)
endif()
# HDF5 through pkg-config: CMake's FindHDF5 compiles a C probe, and ctk is C++ only.
pkg_check_modules(HDF5 QUIET IMPORTED_TARGET hdf5)
if(NOT HDF5_FOUND)
  ctk_missing("HDF5 (hdf5)" libhdf5-dev)
endif()
pkg_check_modules(GEOGRAPHICLIB QUIET IMPORTED_TARGET geographiclib)
if(NOT GEOGRAPHICLIB_FOUND)
  ctk_missing(GeographicLib libgeographiclib-dev)
endif()
# The report pictures are drawn with cairo (text in a real font, antialiased lines).
pkg_check_modules(CAIRO QUIET IMPORTED_TARGET cairo)
if(NOT CAIRO_FOUND)
  ctk_missing("cairo (cairo)" libcairo2-dev)
endif()

if(CTK_BUILD_TESTS)
  ctk_find_package(GTest libgtest-dev)
endif()
if(CTK_BUILD_BENCHMARKS)
  ctk_find_package(benchmark libbenchmark-dev)
endif()
# MPI is optional: without it (or with CTK_WITH_MPI off) every run is one process, as without mpirun.
set(CTK_MPI_FOUND OFF)
if(CTK_WITH_MPI)
  find_package(MPI QUIET COMPONENTS CXX)
  if(MPI_CXX_FOUND)
    set(CTK_MPI_FOUND ON)
  else()
    message(STATUS "ctk: OpenMPI not found (Debian: libopenmpi-dev); runs stay on one process")
  endif()
endif()
