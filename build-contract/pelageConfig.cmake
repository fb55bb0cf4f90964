# CMake package config for pelage (installed by pelage's top-level CMakeLists.txt).
#
#   find_package(pelage 0.1 REQUIRED)
#   target_link_libraries(my_plugin PRIVATE pelage::pelage)
#
# pelage::pelage is the static library libpelage.a (Rust, C API in pelage.h);
# it links the system libraries the Rust standard library needs.

####### Expanded from @PACKAGE_INIT@ by configure_package_config_file() #######
####### Any changes to this file will be overwritten by the next CMake run ####
####### The input file was pelageConfig.cmake.in                            ########

get_filename_component(PACKAGE_PREFIX_DIR "${CMAKE_CURRENT_LIST_DIR}/../../../" ABSOLUTE)

macro(set_and_check _var _file)
  set(${_var} "${_file}")
  if(NOT EXISTS "${_file}")
    message(FATAL_ERROR "File or directory ${_file} referenced by variable ${_var} does not exist !")
  endif()
endmacro()

macro(check_required_components _NAME)
  foreach(comp ${${_NAME}_FIND_COMPONENTS})
    if(NOT ${_NAME}_${comp}_FOUND)
      if(${_NAME}_FIND_REQUIRED_${comp})
        set(${_NAME}_FOUND FALSE)
      endif()
    endif()
  endforeach()
endmacro()

####################################################################################

include(CMakeFindDependencyMacro)
find_dependency(Threads)

set_and_check(pelage_INCLUDE_DIR "${PACKAGE_PREFIX_DIR}/include")
set_and_check(pelage_LIBRARY "${PACKAGE_PREFIX_DIR}/lib/libpelage.a")

if(NOT TARGET pelage::pelage)
  add_library(pelage::pelage STATIC IMPORTED)
  set_target_properties(pelage::pelage PROPERTIES
    IMPORTED_LOCATION "${pelage_LIBRARY}"
    IMPORTED_LINK_INTERFACE_LANGUAGES C
    INTERFACE_INCLUDE_DIRECTORIES "${pelage_INCLUDE_DIR}"
    INTERFACE_LINK_LIBRARIES "Threads::Threads;dl;m")
endif()

set(pelage_LIBRARIES pelage::pelage)
check_required_components(pelage)
