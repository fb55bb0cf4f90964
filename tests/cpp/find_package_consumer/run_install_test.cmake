# Installs the build tree into a temporary prefix, then builds and runs a host
# that finds pelage with find_package(pelage), and one that uses pkg-config.
# Run by CTest (tests/CMakeLists.txt) with -DBUILD_DIR -DCONSUMER_DIR -DWORK_DIR
# -DCONFIG -DGENERATOR -DCXX_COMPILER -DPKG_CONFIG -DEXPECTED_VERSION.
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

set(prefix "${WORK_DIR}/prefix")
file(REMOVE_RECURSE "${WORK_DIR}")
if(NOT CONFIG)
  set(CONFIG Release)
endif()

# 1. install
run("${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${prefix}" --config "${CONFIG}")
file(GLOB_RECURSE installed RELATIVE "${prefix}" "${prefix}/*")
list(SORT installed)
string(REPLACE ";" "\n  " installed_text "${installed}")
message(STATUS "installed:\n  ${installed_text}")

# 2. find_package(pelage) from a separate project
run("${CMAKE_COMMAND}" -S "${CONSUMER_DIR}" -B "${WORK_DIR}/build" -G "${GENERATOR}"
    "-DCMAKE_BUILD_TYPE=${CONFIG}" "-DCMAKE_PREFIX_PATH=${prefix}" "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}"
    "-DPELAGE_WANTED_VERSION=${EXPECTED_VERSION}")
run("${CMAKE_COMMAND}" --build "${WORK_DIR}/build" --config "${CONFIG}")
find_program(consumer consumer PATHS "${WORK_DIR}/build" "${WORK_DIR}/build/${CONFIG}" NO_DEFAULT_PATH REQUIRED)
run("${consumer}")

# 3. pkg-config
if(NOT PKG_CONFIG)
  message(FATAL_ERROR "pkg-config not found (apt-get install pkg-config)")
endif()
file(GLOB_RECURSE pc_files "${prefix}/*/pelage.pc")
list(LENGTH pc_files n)
if(NOT n EQUAL 1)
  message(FATAL_ERROR "expected one installed pelage.pc, found: ${pc_files}")
endif()
get_filename_component(pc_dir "${pc_files}" DIRECTORY)
set(ENV{PKG_CONFIG_PATH} "${pc_dir}")
run("${PKG_CONFIG}" --modversion pelage)
string(STRIP "${RUN_OUTPUT}" version)
if(NOT version STREQUAL EXPECTED_VERSION)
  message(FATAL_ERROR "pkg-config --modversion pelage: ${version}, expected ${EXPECTED_VERSION}")
endif()
run("${PKG_CONFIG}" --cflags --libs pelage)
string(STRIP "${RUN_OUTPUT}" flags)
separate_arguments(flags UNIX_COMMAND "${flags}")
run("${CXX_COMPILER}" -std=c++17 "${CONSUMER_DIR}/main.cpp" -o "${WORK_DIR}/pkg_config_consumer" ${flags})
run("${WORK_DIR}/pkg_config_consumer")
message(STATUS "find_package(pelage) and pkg-config consumers both work")
