# The library as an embedder gets it: a library-only configure of the source
# tree (examples and tests off; Embree, TBB, libpng, tinyobjloader disabled
# and no C++ compiler, so nothing but cmake, a C compiler and cargo can be
# used), built and installed into a temporary prefix. Then hosts outside the
# tree link it: C++ through find_package(pelage <this version>) and C
# (cpp_examples/minimal.c) through pkg-config, each against the static and
# the shared library, and each runs.
# Run by CTest (tests/CMakeLists.txt) with -DSOURCE_DIR -DCONSUMER_DIR -DWORK_DIR
# -DGENERATOR -DC_COMPILER -DCXX_COMPILER -DPKG_CONFIG -DREADELF -DEXPECTED_VERSION.
cmake_minimum_required(VERSION 3.25)

function(run)
  string(REPLACE ";" " " shown "${ARGN}")
  message(STATUS "$ ${shown}")
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(out)
    message(STATUS "${out}")
  endif()
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}):\n${out}\n${err}")
  endif()
  set(RUN_OUTPUT "${out}" PARENT_SCOPE)
endfunction()

# Like run, without echoing the output (readelf listings).
function(probe)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " shown "${ARGN}")
    message(FATAL_ERROR "${shown} failed (${rc}):\n${err}")
  endif()
  set(RUN_OUTPUT "${out}" PARENT_SCOPE)
endfunction()

# The shared library a binary needs by name (its NEEDED entries).
function(needs binary out)
  probe("${READELF}" -d "${binary}")
  string(REGEX MATCHALL "Shared library: \\[[^]]*\\]" needed "${RUN_OUTPUT}")
  set(${out} "${needed}" PARENT_SCOPE)
endfunction()

function(expect_linked binary kind)
  needs("${binary}" needed)
  string(FIND "${needed}" "[libpelage.so.${SONAME_VERSION}]" at)
  if(kind STREQUAL "shared" AND at EQUAL -1)
    message(FATAL_ERROR "${binary} does not need libpelage.so.${SONAME_VERSION}: ${needed}")
  elseif(kind STREQUAL "static" AND NOT at EQUAL -1)
    message(FATAL_ERROR "${binary} was to link the static library but needs ${needed}")
  endif()
  file(SIZE "${binary}" size)
  message(STATUS "${binary}: ${kind}, ${size} bytes")
endfunction()

set(prefix "${WORK_DIR}/prefix")
set(build "${WORK_DIR}/library-build")
file(REMOVE_RECURSE "${WORK_DIR}")
# the SONAME's version: MAJOR.MINOR before 1.0, MAJOR from 1.0 (capi/build.rs)
string(REGEX REPLACE "^([0-9]+)\\.([0-9]+).*" "\\1" SONAME_VERSION_MAJOR "${EXPECTED_VERSION}")
string(REGEX REPLACE "^[0-9]+\\.([0-9]+).*" "\\1" SONAME_VERSION_MINOR "${EXPECTED_VERSION}")
if(SONAME_VERSION_MAJOR EQUAL 0)
  set(SONAME_VERSION "0.${SONAME_VERSION_MINOR}")
else()
  set(SONAME_VERSION "${SONAME_VERSION_MAJOR}")
endif()

# 1. the library alone: configure, build, install
run("${CMAKE_COMMAND}" -S "${SOURCE_DIR}" -B "${build}" -G "${GENERATOR}" -DCMAKE_BUILD_TYPE=Release
    "-DCMAKE_C_COMPILER=${C_COMPILER}"
    -DPELAGE_BUILD_EXAMPLES=OFF -DPELAGE_BUILD_TESTS=OFF
    -DCMAKE_CXX_COMPILER=/nonexistent/c++
    -DCMAKE_DISABLE_FIND_PACKAGE_embree=ON -DCMAKE_DISABLE_FIND_PACKAGE_TBB=ON
    -DCMAKE_DISABLE_FIND_PACKAGE_PNG=ON -DCMAKE_DISABLE_FIND_PACKAGE_tinyobjloader=ON)
run("${CMAKE_COMMAND}" --build "${build}")
run("${CMAKE_COMMAND}" --install "${build}" --prefix "${prefix}")
file(GLOB_RECURSE installed LIST_DIRECTORIES false RELATIVE "${prefix}" "${prefix}/*")
list(SORT installed)
string(REPLACE ";" "\n  " installed_text "${installed}")
message(STATUS "installed:\n  ${installed_text}")
file(GLOB libdir_files "${prefix}/*/libpelage.a")
get_filename_component(libdir "${libdir_files}" DIRECTORY)
foreach(file libpelage.a libpelage.so libpelage.so.${SONAME_VERSION} libpelage.so.${EXPECTED_VERSION}
             libpelage.so.${EXPECTED_VERSION}.debug)
  if(NOT EXISTS "${libdir}/${file}")
    message(FATAL_ERROR "not installed: ${libdir}/${file}")
  endif()
endforeach()
probe("${READELF}" -d "${libdir}/libpelage.so.${EXPECTED_VERSION}")
if(NOT RUN_OUTPUT MATCHES "Library soname: \\[libpelage\\.so\\.${SONAME_VERSION}\\]")
  message(FATAL_ERROR "libpelage.so has no SONAME libpelage.so.${SONAME_VERSION}")
endif()
# stripped, with the shared library's debug info split beside it
foreach(file libpelage.a libpelage.so.${EXPECTED_VERSION})
  probe("${READELF}" -S -W "${libdir}/${file}")
  if(RUN_OUTPUT MATCHES "\\.debug_info")
    message(FATAL_ERROR "${file} still carries debug info")
  endif()
  file(SIZE "${libdir}/${file}" size)
  message(STATUS "${file}: ${size} bytes")
endforeach()
probe("${READELF}" -S -W "${libdir}/libpelage.so.${EXPECTED_VERSION}.debug")
if(NOT RUN_OUTPUT MATCHES "\\.debug_info")
  message(FATAL_ERROR "libpelage.so.${EXPECTED_VERSION}.debug holds no debug info")
endif()

# 2. C++ through find_package(pelage <this version>), static and shared
run("${CMAKE_COMMAND}" -S "${CONSUMER_DIR}" -B "${WORK_DIR}/consumer" -G "${GENERATOR}"
    -DCMAKE_BUILD_TYPE=Release "-DCMAKE_PREFIX_PATH=${prefix}" "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}"
    "-DPELAGE_WANTED_VERSION=${EXPECTED_VERSION}")
if(NOT RUN_OUTPUT MATCHES "Found pelage ${EXPECTED_VERSION}")
  message(FATAL_ERROR "find_package(pelage) did not report version ${EXPECTED_VERSION}")
endif()
run("${CMAKE_COMMAND}" --build "${WORK_DIR}/consumer")
# the promised rule: before 1.0 another minor version is refused, by name
string(REGEX MATCH "^[0-9]+" major "${EXPECTED_VERSION}")
if(major STREQUAL "0" AND SONAME_VERSION_MINOR GREATER 0)
  math(EXPR older "${SONAME_VERSION_MINOR} - 1")
  execute_process(
    COMMAND "${CMAKE_COMMAND}" -S "${CONSUMER_DIR}" -B "${WORK_DIR}/consumer-older" -G "${GENERATOR}"
            "-DCMAKE_PREFIX_PATH=${prefix}" "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}"
            "-DPELAGE_WANTED_VERSION=0.${older}"
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc EQUAL 0 OR NOT err MATCHES "version: ${EXPECTED_VERSION}")
    message(FATAL_ERROR "find_package(pelage 0.${older}) should refuse ${EXPECTED_VERSION}:\n${err}")
  endif()
  message(STATUS "find_package(pelage 0.${older}) refuses ${EXPECTED_VERSION}, as promised")
endif()
foreach(kind static shared)
  run("${WORK_DIR}/consumer/consumer_${kind}")
  expect_linked("${WORK_DIR}/consumer/consumer_${kind}" ${kind})
endforeach()

# 3. C through pkg-config: pelage-static and pelage (shared)
if(NOT PKG_CONFIG)
  message(FATAL_ERROR "pkg-config not found (apt-get install pkg-config)")
endif()
set(ENV{PKG_CONFIG_PATH} "${libdir}/pkgconfig")
foreach(pc pelage pelage-static)
  run("${PKG_CONFIG}" --modversion ${pc})
  string(STRIP "${RUN_OUTPUT}" version)
  if(NOT version STREQUAL EXPECTED_VERSION)
    message(FATAL_ERROR "pkg-config --modversion ${pc}: ${version}, expected ${EXPECTED_VERSION}")
  endif()
endforeach()
foreach(kind static shared)
  set(pc pelage-static)
  set(extra "")
  if(kind STREQUAL "shared")
    set(pc pelage)
    set(extra "-Wl,-rpath,${libdir}")
  endif()
  run("${PKG_CONFIG}" --cflags --libs ${pc})
  string(STRIP "${RUN_OUTPUT}" flags)
  separate_arguments(flags UNIX_COMMAND "${flags}")
  run("${C_COMPILER}" -std=c99 "${SOURCE_DIR}/cpp_examples/minimal.c" -o "${WORK_DIR}/minimal_${kind}" ${flags} ${extra})
  run("${WORK_DIR}/minimal_${kind}")
  expect_linked("${WORK_DIR}/minimal_${kind}" ${kind})
endforeach()
message(STATUS "library-only install; find_package and pkg-config consumers, static and shared, all run")
