# cmake -DSOURCE_DIR=python -DPROJECT_FILES_DIR=... -DLIBRARY=libparticlemesh.so [-DPCL_LIBRARY=...]
#       -DPATCHELF=/usr/bin/patchelf -DDEST=build/python -DSTAMP=... -P stage_python_package.cmake
#
# Stages the Python package as it ships (pip's project folder, the add-on's particlemesh/
# folder): DEST/particlemesh/*.py from SOURCE_DIR/particlemesh, and in DEST/particlemesh/lib/
# libparticlemesh.so with every library it needs beyond the C and C++ runtime (glibc's
# libraries, libstdc++, libgcc_s, libz), each under the name its users ask for (its soname)
# and with RUNPATH $ORIGIN, so that the folder works on a Linux without those packages
# (Blender from blender.org, a bare Debian). Their Debian licence files go to lib/licenses/,
# with a README naming each library's package and version. The optional PCL bridge is
# copied with RUNPATH $ORIGIN too, but PCL itself stays a system requirement (it is big and
# only .pcd input needs it).
foreach(var SOURCE_DIR PROJECT_FILES_DIR LIBRARY PATCHELF DEST STAMP)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "stage_python_package.cmake: ${var} is not set")
  endif()
endforeach()

set(pkg "${DEST}/particlemesh")
set(lib "${pkg}/lib")
file(REMOVE_RECURSE "${DEST}")
file(MAKE_DIRECTORY "${lib}/licenses")
# Every .py, subpackages included.
file(COPY "${SOURCE_DIR}/particlemesh" DESTINATION "${DEST}" FILES_MATCHING PATTERN "*.py"
     PATTERN "__pycache__" EXCLUDE)
file(GLOB project_files "${PROJECT_FILES_DIR}/*")
file(COPY ${project_files} DESTINATION "${DEST}")

# The C/C++ runtime every Linux has (and Blender itself loads): not bundled.
set(system_runtime
  "^ld-linux" "^linux-vdso" "^libc\\.so" "^libm\\.so" "^libstdc\\+\\+\\.so" "^libgcc_s\\.so"
  "^libpthread\\.so" "^libdl\\.so" "^librt\\.so" "^libz\\.so")
file(GET_RUNTIME_DEPENDENCIES
  LIBRARIES "${LIBRARY}"
  RESOLVED_DEPENDENCIES_VAR resolved
  UNRESOLVED_DEPENDENCIES_VAR unresolved
  CONFLICTING_DEPENDENCIES_PREFIX conflicting
  PRE_EXCLUDE_REGEXES ${system_runtime})
if(unresolved)
  message(FATAL_ERROR "stage_python_package.cmake: ${LIBRARY} needs ${unresolved}, which the "
                      "dynamic loader does not find")
endif()

# Under its plain name: ctypes loads lib/libparticlemesh.so by path (zip archives keep no
# symbolic links); the PCL bridge finds it by its soname, which the loader records.
file(COPY_FILE "${LIBRARY}" "${lib}/libparticlemesh.so")
set(bundled "${lib}/libparticlemesh.so")
set(readme "Libraries bundled with libparticlemesh.so, from Debian, with their licences:\n\n")
foreach(dep IN LISTS resolved)
  get_filename_component(name "${dep}" NAME)  # the name asked for (the soname)
  file(REAL_PATH "${dep}" real)
  file(COPY_FILE "${real}" "${lib}/${name}")
  list(APPEND bundled "${lib}/${name}")
  execute_process(COMMAND dpkg-query -S "${real}" OUTPUT_VARIABLE owner RESULT_VARIABLE rc
                  ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(NOT rc EQUAL 0 AND real MATCHES "^/usr(/lib/.*)")
    # Debian 12 merges /lib into /usr/lib, but some packages (liblzma5) still list their
    # files under /lib.
    execute_process(COMMAND dpkg-query -S "${CMAKE_MATCH_1}" OUTPUT_VARIABLE owner RESULT_VARIABLE rc
                    ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
  endif()
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "stage_python_package.cmake: no Debian package owns ${real}; its "
                        "licence cannot be bundled")
  endif()
  string(REGEX REPLACE ":.*" "" package "${owner}")
  execute_process(COMMAND dpkg-query -W -f=\${Version} "${package}" OUTPUT_VARIABLE version
                  OUTPUT_STRIP_TRAILING_WHITESPACE)
  set(copyright "/usr/share/doc/${package}/copyright")
  if(NOT EXISTS "${copyright}")
    message(FATAL_ERROR "stage_python_package.cmake: ${copyright} (the licence of ${name}) is missing")
  endif()
  file(COPY_FILE "${copyright}" "${lib}/licenses/${package}.copyright")
  string(APPEND readme "  ${name}: Debian package ${package} ${version}, licenses/${package}.copyright\n")
endforeach()
file(WRITE "${lib}/licenses/README" "${readme}")

if(PCL_LIBRARY)
  file(COPY_FILE "${PCL_LIBRARY}" "${lib}/libparticlemesh_pcl.so")
  list(APPEND bundled "${lib}/libparticlemesh_pcl.so")
endif()
foreach(file IN LISTS bundled)
  # Writable first: Debian installs its libraries read-only for others, and patchelf rewrites.
  file(CHMOD "${file}" PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE
                                   WORLD_READ WORLD_EXECUTE)
  execute_process(COMMAND "${PATCHELF}" --set-rpath "$ORIGIN" "${file}" RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "stage_python_package.cmake: patchelf failed on ${file}")
  endif()
endforeach()
file(TOUCH "${STAMP}")
