# OpenMM ships no CMake config on Debian: locate the header and library by hand.
# Defines OpenMM_FOUND and the imported target OpenMM::OpenMM.
find_path(OpenMM_INCLUDE_DIR OpenMM.h PATH_SUFFIXES openmm)
find_library(OpenMM_LIBRARY OpenMM)
find_path(OpenMM_PLUGIN_DIR libOpenMMCPU.so
  PATHS /usr/lib/x86_64-linux-gnu/openmm/plugins /usr/lib/openmm/plugins /usr/local/lib/plugins
  NO_DEFAULT_PATH)

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(OpenMM REQUIRED_VARS OpenMM_LIBRARY OpenMM_INCLUDE_DIR)

if(OpenMM_FOUND AND NOT TARGET OpenMM::OpenMM)
  add_library(OpenMM::OpenMM UNKNOWN IMPORTED)
  set_target_properties(OpenMM::OpenMM PROPERTIES
    IMPORTED_LOCATION "${OpenMM_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${OpenMM_INCLUDE_DIR}")
endif()
mark_as_advanced(OpenMM_INCLUDE_DIR OpenMM_LIBRARY OpenMM_PLUGIN_DIR)
