# Third-party dependencies, all from Debian 12 packages (see scripts/setup.sh).
find_package(Threads REQUIRED)
find_package(TBB REQUIRED)
find_package(OpenMesh REQUIRED)  # targets OpenMeshCore, OpenMeshTools
find_package(Eigen3 REQUIRED NO_MODULE)
find_package(PNG REQUIRED)       # libpng16 (Debian's libpng-dev): the renderer's PNG output
find_package(ZLIB REQUIRED)      # zlib1g-dev: gzip .bgeo, zlib-compressed VTK XML arrays
find_package(LibLZMA REQUIRED)   # liblzma-dev: LZMA-compressed VTK XML arrays (.xz streams)
# liblz4-dev: LZ4-compressed VTK XML arrays. It ships a pkg-config file, not a CMake package.
find_package(PkgConfig REQUIRED)
pkg_check_modules(PM_LZ4 REQUIRED IMPORTED_TARGET liblz4)
# libblosc-dev: Houdini's .bgeo.sc (Blosc-compressed blocks in SideFX's SCF container).
pkg_check_modules(PM_BLOSC REQUIRED IMPORTED_TARGET blosc)
# nlohmann-json3-dev (header-only): the CLI's JSON reports, the library's .series collections.
find_package(nlohmann_json REQUIRED)
if(PM_BUILD_CLI)
  find_package(CLI11 REQUIRED)
endif()
if(PM_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(PM_BUILD_BENCH)
  find_package(benchmark REQUIRED)
endif()

# OpenSubdiv (smooth/: Loop subdivision). Debian's OpenSubdivConfig.cmake is broken, so the
# CPU library and the headers are found directly and wrapped in an imported target.
if(NOT TARGET particlemesh_opensubdiv)
  find_path(PM_OPENSUBDIV_INCLUDE_DIR opensubdiv/far/topologyRefiner.h REQUIRED)
  find_library(PM_OPENSUBDIV_CPU_LIBRARY NAMES osdCPU REQUIRED)
  add_library(particlemesh_opensubdiv UNKNOWN IMPORTED)
  set_target_properties(particlemesh_opensubdiv PROPERTIES
    IMPORTED_LOCATION "${PM_OPENSUBDIV_CPU_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${PM_OPENSUBDIV_INCLUDE_DIR}")
endif()

if(PM_WITH_PCL)
  # Debian's PCL config pulls in VTK, whose targets need MPI::MPI_C (C is enabled in project()).
  find_package(MPI COMPONENTS C)
  find_package(PCL 1.13 REQUIRED COMPONENTS common io search kdtree surface filters features)
endif()
