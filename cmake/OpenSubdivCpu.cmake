# OpenSubdiv's CPU library as the target yarf::opensubdiv. Debian's CMake
# package for it names static libraries the package does not ship, so
# find_package(OpenSubdiv) fails: the library and headers are found here.
if(NOT TARGET yarf::opensubdiv)
  find_library(YARF_OSD_CPU_LIBRARY osdCPU REQUIRED)
  find_path(YARF_OSD_INCLUDE_DIR opensubdiv/far/topologyRefiner.h REQUIRED)
  add_library(yarf_opensubdiv INTERFACE)
  add_library(yarf::opensubdiv ALIAS yarf_opensubdiv)
  target_link_libraries(yarf_opensubdiv INTERFACE "${YARF_OSD_CPU_LIBRARY}")
  target_include_directories(yarf_opensubdiv SYSTEM INTERFACE "${YARF_OSD_INCLUDE_DIR}")
endif()
