# Every dependency comes from a Debian package; a missing one stops configuration
# with the package to install, because that is the only thing a user can act on.
function(deli_missing what package)
  message(FATAL_ERROR
    "deli: ${what} not found. Install it with:\n  apt-get install ${package}\n"
    "(or run ./setup.sh, which installs everything deli needs)")
endfunction()

find_package(Eigen3 3.3 QUIET NO_MODULE)
if(NOT Eigen3_FOUND)
  deli_missing("Eigen 3" libeigen3-dev)
endif()

find_package(HDF5 QUIET COMPONENTS C)
if(NOT HDF5_FOUND)
  deli_missing("HDF5 (C library)" libhdf5-dev)
endif()

find_package(tomlplusplus 3 QUIET)
if(NOT tomlplusplus_FOUND)
  deli_missing("toml++" libtomlplusplus-dev)
endif()

# OpenMM and LAMMPS serve deli validate and the cross-check tests only.
if(DELI_CROSSCHECK)
  find_package(OpenMM QUIET)
  if(NOT OpenMM_FOUND)
    deli_missing("OpenMM" "libopenmm-dev libopenmm-plugins")
  endif()

  # LAMMPS by pkg-config first: Debian's liblammps-dev ships a CMake config whose
  # LAMMPS::lmp target names /usr/bin/lmp, a file of another package (lammps), so
  # find_package(LAMMPS) stops configuration on a machine without it. The config is
  # only the fallback, for a LAMMPS built from source with no .pc file.
  find_package(PkgConfig QUIET)
  if(PkgConfig_FOUND)
    pkg_check_modules(LAMMPS_PC QUIET IMPORTED_TARGET liblammps)
  endif()
  if(LAMMPS_PC_FOUND)
    # The .pc file names /usr/include; the C library header is in its lammps/ folder.
    find_path(LAMMPS_LIBRARY_H_DIR library.h PATH_SUFFIXES lammps
              HINTS "${LAMMPS_PC_INCLUDEDIR}" NO_DEFAULT_PATH)
    if(NOT LAMMPS_LIBRARY_H_DIR)
      deli_missing("LAMMPS' library.h" liblammps-dev)
    endif()
    add_library(deli_lammps INTERFACE)
    target_link_libraries(deli_lammps INTERFACE PkgConfig::LAMMPS_PC)
    target_include_directories(deli_lammps INTERFACE "${LAMMPS_LIBRARY_H_DIR}")
    add_library(LAMMPS::lammps ALIAS deli_lammps)
    message(STATUS "deli: LAMMPS ${LAMMPS_PC_VERSION} from pkg-config (liblammps)")
  else()
    find_package(LAMMPS QUIET)
    if(NOT LAMMPS_FOUND)
      deli_missing("LAMMPS library" "liblammps-dev pkg-config")
    endif()
    message(STATUS "deli: LAMMPS ${LAMMPS_VERSION} from its CMake config")
  endif()
endif()

if(DELI_BUILD_TESTS)
  find_package(GTest QUIET)
  if(NOT GTest_FOUND)
    deli_missing("GoogleTest" libgtest-dev)
  endif()
endif()
