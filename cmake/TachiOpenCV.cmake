# tachi_find_opencv(module...): the imported targets opencv_<module> (core, imgproc, imgcodecs, highgui,
# videoio) that sensor/ and viewer/ link.
#
# With libopencv-dev installed (scripts/setup.sh, the full setup) they come from OpenCV's own CMake package.
# README command (1) installs only the module -dev packages the demo uses (setup.sh --demo:
# libopencv-{core,imgproc,imgcodecs,highgui,videoio}-dev): they carry the headers and the libraries, but
# OpenCVConfig.cmake is in libopencv-dev alone, which depends on every OpenCV module (contrib, viz, dnn ...:
# 51 more packages, 61 MB, docs/testing.md). Then the same targets are made here from the headers and
# libraries, with the include directory and the links between modules that OpenCV's package gives them.
include_guard(GLOBAL)

# Each module's OpenCV dependencies (OpenCVModules.cmake of Debian's 4.6).
set(_tachi_opencv_deps_core "")
set(_tachi_opencv_deps_imgproc core)
set(_tachi_opencv_deps_imgcodecs core imgproc)
set(_tachi_opencv_deps_videoio core imgproc imgcodecs)
set(_tachi_opencv_deps_highgui core imgproc imgcodecs videoio)

function(tachi_find_opencv)
  find_package(OpenCV QUIET COMPONENTS ${ARGN})
  if(OpenCV_FOUND)
    return()
  endif()
  # The requested modules and the ones they need, dependencies first.
  set(modules "")
  foreach(module IN LISTS ARGN)
    if(NOT DEFINED _tachi_opencv_deps_${module})
      message(FATAL_ERROR "tachi_find_opencv: no fallback for OpenCV module '${module}'; install libopencv-dev")
    endif()
    list(APPEND modules ${_tachi_opencv_deps_${module}} ${module})
  endforeach()
  list(REMOVE_DUPLICATES modules)
  find_path(TACHI_OPENCV_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4)
  if(NOT TACHI_OPENCV_INCLUDE_DIR)
    message(FATAL_ERROR "OpenCV not found: neither OpenCVConfig.cmake (libopencv-dev) nor opencv2/core.hpp "
                        "(libopencv-core-dev); run scripts/setup.sh")
  endif()
  # The links between modules above are 4.x's; another major version may link its modules otherwise, which
  # would surface as undefined symbols at link time. Say so here instead.
  file(STRINGS "${TACHI_OPENCV_INCLUDE_DIR}/opencv2/core/version.hpp" _tachi_cv_major REGEX "#define CV_VERSION_MAJOR")
  string(REGEX MATCH "[0-9]+" _tachi_cv_major "${_tachi_cv_major}")
  if(NOT _tachi_cv_major STREQUAL "4")
    message(FATAL_ERROR "OpenCV ${_tachi_cv_major}.x in ${TACHI_OPENCV_INCLUDE_DIR} without its CMake package: the "
                        "fallback here knows 4.x's modules only; install libopencv-dev (scripts/setup.sh)")
  endif()
  foreach(module IN LISTS modules)
    if(TARGET opencv_${module})
      continue()
    endif()
    find_library(TACHI_OPENCV_${module}_LIBRARY opencv_${module})
    if(NOT TACHI_OPENCV_${module}_LIBRARY OR NOT EXISTS "${TACHI_OPENCV_INCLUDE_DIR}/opencv2/${module}.hpp")
      message(FATAL_ERROR "OpenCV module ${module} not found (libopencv-${module}-dev); run scripts/setup.sh")
    endif()
    add_library(opencv_${module} SHARED IMPORTED GLOBAL)
    set(links "")
    foreach(dep IN LISTS _tachi_opencv_deps_${module})
      list(APPEND links opencv_${dep})
    endforeach()
    set_target_properties(opencv_${module} PROPERTIES
      IMPORTED_LOCATION "${TACHI_OPENCV_${module}_LIBRARY}"
      INTERFACE_INCLUDE_DIRECTORIES "${TACHI_OPENCV_INCLUDE_DIR}"
      INTERFACE_LINK_LIBRARIES "${links}")
  endforeach()
  message(STATUS "OpenCV: no OpenCVConfig.cmake (libopencv-dev); modules ${modules} from ${TACHI_OPENCV_INCLUDE_DIR}")
endfunction()
