# OpenCV's modules ctk uses (core, imgproc) as the targets OpenCV's own package names
# them. Debian ships OpenCVConfig.cmake only in libopencv-dev, which pulls in every OpenCV module
# and its dependencies (about 412 MB); the per-module packages (libopencv-core-dev,
# libopencv-imgproc-dev) hold the headers and libraries alone. So: OpenCV's
# package where it is installed, else imported targets of the same names. Included by the build and
# by the installed ctkConfig.cmake.
if(NOT TARGET opencv_core)
  find_package(OpenCV QUIET COMPONENTS core imgproc)
endif()
if(NOT TARGET opencv_core)
  find_path(CTK_OPENCV_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4)
  set(ctk_opencv_needs "")
  foreach(module core imgproc)
    find_library(CTK_OPENCV_${module}_LIBRARY opencv_${module})
    if(NOT CTK_OPENCV_INCLUDE_DIR OR NOT CTK_OPENCV_${module}_LIBRARY)
      set(OpenCV_FOUND FALSE)
      return()
    endif()
    add_library(opencv_${module} SHARED IMPORTED)
    set_target_properties(opencv_${module} PROPERTIES
      IMPORTED_LOCATION "${CTK_OPENCV_${module}_LIBRARY}"
      INTERFACE_INCLUDE_DIRECTORIES "${CTK_OPENCV_INCLUDE_DIR}"
      INTERFACE_LINK_LIBRARIES "${ctk_opencv_needs}")
    list(APPEND ctk_opencv_needs opencv_${module})
  endforeach()
endif()
set(OpenCV_FOUND TRUE)
