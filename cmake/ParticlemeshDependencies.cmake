# Third-party dependencies, all from Debian 12 packages (see scripts/setup.sh).
find_package(Threads REQUIRED)
find_package(TBB REQUIRED)
find_package(OpenMesh REQUIRED)  # targets OpenMeshCore, OpenMeshTools
if(PM_BUILD_CLI)
  find_package(CLI11 REQUIRED)
  find_package(nlohmann_json REQUIRED)
endif()
if(PM_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(PM_BUILD_BENCH)
  find_package(benchmark REQUIRED)
endif()
if(PM_WITH_PCL)
  # Debian's PCL config pulls in VTK, whose targets need MPI::MPI_C (C is enabled in project()).
  find_package(MPI COMPONENTS C)
  find_package(PCL 1.13 REQUIRED COMPONENTS common io search kdtree surface filters features)
endif()
