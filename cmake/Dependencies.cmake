# SPDX-License-Identifier: MIT
# Every dependency comes from a Debian package; a missing one stops configuration and names it.
include(FindPackageHandleStandardArgs)

function(mscale_need found pkg what)
  if(NOT ${found})
    message(FATAL_ERROR "mscale needs ${what}: install the Debian package(s) '${pkg}' "
                        "(apt-get install ${pkg}), or run ./setup.sh")
  endif()
endfunction()

find_package(MPI COMPONENTS C QUIET)
mscale_need(MPI_C_FOUND "libopenmpi-dev openmpi-bin" "MPI (Open MPI)")

set(HDF5_PREFER_PARALLEL TRUE)
find_package(HDF5 COMPONENTS C QUIET)
mscale_need(HDF5_FOUND "libhdf5-openmpi-dev" "HDF5 (parallel, Open MPI flavour)")
if(NOT HDF5_IS_PARALLEL)
  message(FATAL_ERROR "mscale needs the parallel (Open MPI) HDF5: apt-get install libhdf5-openmpi-dev")
endif()

find_package(SUNDIALS CONFIG QUIET)
mscale_need(SUNDIALS_FOUND "libsundials-dev" "SUNDIALS (KINSOL, CVODE)")

find_package(PkgConfig QUIET)
mscale_need(PKG_CONFIG_FOUND "pkg-config" "pkg-config")
pkg_check_modules(YAML QUIET IMPORTED_TARGET yaml-0.1)
mscale_need(YAML_FOUND "libyaml-dev" "libyaml")

find_path(METIS_INCLUDE_DIR metis.h)
find_library(METIS_LIBRARY metis)
if(METIS_INCLUDE_DIR AND METIS_LIBRARY)
  set(METIS_OK TRUE)
endif()
mscale_need(METIS_OK "libmetis-dev" "METIS")
add_library(mscale_metis INTERFACE)
target_include_directories(mscale_metis INTERFACE ${METIS_INCLUDE_DIR})
target_link_libraries(mscale_metis INTERFACE ${METIS_LIBRARY})

find_package(OpenMP COMPONENTS C QUIET)
mscale_need(OpenMP_C_FOUND "libgomp1 (part of gcc)" "OpenMP")

add_library(mscale_hdf5 INTERFACE)
target_include_directories(mscale_hdf5 INTERFACE ${HDF5_C_INCLUDE_DIRS})
target_link_libraries(mscale_hdf5 INTERFACE ${HDF5_C_LIBRARIES} MPI::MPI_C)
target_compile_definitions(mscale_hdf5 INTERFACE ${HDF5_C_DEFINITIONS})

if(MSCALE_TESTS)
  find_package(cmocka CONFIG QUIET)
  if(NOT cmocka_FOUND)
    find_path(CMOCKA_INCLUDE_DIR cmocka.h)
    find_library(CMOCKA_LIBRARY cmocka)
    if(CMOCKA_INCLUDE_DIR AND CMOCKA_LIBRARY)
      set(cmocka_FOUND TRUE)
    endif()
  endif()
  mscale_need(cmocka_FOUND "libcmocka-dev" "cmocka (unit tests)")
  find_path(CMOCKA_INCLUDE_DIR cmocka.h)
  find_library(CMOCKA_LIBRARY cmocka)
  add_library(mscale_cmocka INTERFACE)
  target_include_directories(mscale_cmocka INTERFACE ${CMOCKA_INCLUDE_DIR})
  target_link_libraries(mscale_cmocka INTERFACE ${CMOCKA_LIBRARY})
endif()
