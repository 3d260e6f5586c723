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

find_package(OpenMM QUIET)
if(NOT OpenMM_FOUND)
  deli_missing("OpenMM" "libopenmm-dev libopenmm-plugins")
endif()

# LAMMPS' CMake config drags in MPI; fall back to pkg-config when either is absent.
find_package(LAMMPS QUIET)
if(NOT LAMMPS_FOUND)
  find_package(PkgConfig QUIET)
  if(PkgConfig_FOUND)
    pkg_check_modules(LAMMPS_PC QUIET IMPORTED_TARGET liblammps)
  endif()
  if(NOT LAMMPS_PC_FOUND)
    deli_missing("LAMMPS library" "liblammps-dev pkg-config")
  endif()
  add_library(LAMMPS::lammps ALIAS PkgConfig::LAMMPS_PC)
endif()

if(DELI_BUILD_TESTS)
  find_package(GTest QUIET)
  if(NOT GTest_FOUND)
    deli_missing("GoogleTest" libgtest-dev)
  endif()
endif()
