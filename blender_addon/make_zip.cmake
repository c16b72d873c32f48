# cmake -DSOURCE_DIR=... -DLIBRARY=... -DSTAGE_DIR=... -DZIP=... -P make_zip.cmake
# Stages particlemesh/ (Python files, manifest, lib/libparticlemesh.so and, with -DPCL_LIBRARY=...,
# lib/libparticlemesh_pcl.so) and zips it.
foreach(var SOURCE_DIR LIBRARY STAGE_DIR ZIP)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "make_zip.cmake: ${var} is not set")
  endif()
endforeach()

file(REMOVE_RECURSE "${STAGE_DIR}")
file(MAKE_DIRECTORY "${STAGE_DIR}/particlemesh/lib")
file(GLOB files "${SOURCE_DIR}/*.py" "${SOURCE_DIR}/blender_manifest.toml")
file(COPY ${files} DESTINATION "${STAGE_DIR}/particlemesh")
# Under its plain name: zip archives keep no symbolic links, and native.py loads
# lib/libparticlemesh.so* by path (the soname does not matter then).
file(COPY_FILE "${LIBRARY}" "${STAGE_DIR}/particlemesh/lib/libparticlemesh.so")
# The PCL bridge (.pcd import), optional. Its DT_NEEDED libparticlemesh.so.<major>.<minor> is
# the soname of the copy above, which native.py always loads first (the dynamic loader matches
# an already loaded library by its soname); its own RUNPATH, which points into the build
# tree, becomes $ORIGIN. PCL itself comes from the system (Debian's libpcl-io etc.).
if(PCL_LIBRARY)
  set(bridge "${STAGE_DIR}/particlemesh/lib/libparticlemesh_pcl.so")
  file(COPY_FILE "${PCL_LIBRARY}" "${bridge}")
  file(RPATH_SET FILE "${bridge}" NEW_RPATH "$ORIGIN")
endif()

file(REMOVE "${ZIP}")
execute_process(
  COMMAND "${CMAKE_COMMAND}" -E tar cf "${ZIP}" --format=zip --mtime=2000-01-01 particlemesh
  WORKING_DIRECTORY "${STAGE_DIR}"
  RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "make_zip.cmake: zipping failed (${rc})")
endif()
