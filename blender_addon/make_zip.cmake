# cmake -DSOURCE_DIR=... -DPACKAGE_DIR=... -DSTAGE_DIR=... -DZIP=... -P make_zip.cmake
# Stages particlemesh/ (the add-on's Python files and manifest) with the staged Python package
# (PACKAGE_DIR: its sources and lib/ with libparticlemesh.so, the libraries it needs, their
# licences and the optional PCL bridge) as particlemesh/particlemesh/, and zips it.
foreach(var SOURCE_DIR PACKAGE_DIR STAGE_DIR ZIP)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "make_zip.cmake: ${var} is not set")
  endif()
endforeach()

file(REMOVE_RECURSE "${STAGE_DIR}")
file(MAKE_DIRECTORY "${STAGE_DIR}/particlemesh")
file(GLOB files "${SOURCE_DIR}/*.py" "${SOURCE_DIR}/blender_manifest.toml")
file(COPY ${files} DESTINATION "${STAGE_DIR}/particlemesh")
file(COPY "${PACKAGE_DIR}" DESTINATION "${STAGE_DIR}/particlemesh"
     PATTERN "__pycache__" EXCLUDE PATTERN "*.pyc" EXCLUDE)

file(REMOVE "${ZIP}")
execute_process(
  COMMAND "${CMAKE_COMMAND}" -E tar cf "${ZIP}" --format=zip --mtime=2000-01-01 particlemesh
  WORKING_DIRECTORY "${STAGE_DIR}"
  RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "make_zip.cmake: zipping failed (${rc})")
endif()
