# Embree 3 baseline for the benchmark (included OPTIONAL from bench/CMakeLists.txt).
#
# Defines, when Embree 3 is available:
#   ct_embree_baseline    STATIC library (bench/embree_baseline.cpp), PUBLIC
#                         include dir bench/, linked to Embree
#   test_embree_baseline  test executable, registered with add_test
# and sets CT_HAVE_EMBREE (ON/OFF) in the including scope.
#
# Lookup order:
#   1. find_package(embree 3 CONFIG) -- Debian 12 ships
#      /usr/lib/x86_64-linux-gnu/cmake/embree-3.13.5/embree-config.cmake with an
#      imported target `embree`.  That config file calls
#      find_package(TBB REQUIRED) when Embree was built with the TBB tasking
#      system, which aborts configure if TBB's CMake config is missing, so we
#      only try it once TBB's config is known to be findable.
#   2. find_path/find_library fallback (embree3/rtcore.h + libembree3).
# Set CT_WITH_EMBREE=OFF to skip the baseline altogether.

option(CT_WITH_EMBREE "Build the Embree 3 benchmark baseline if Embree is found" ON)

set(CT_HAVE_EMBREE OFF)
set(_ct_embree_target "")
set(_ct_embree_how "")

if(CT_WITH_EMBREE)
  find_package(TBB CONFIG QUIET)
  if(TBB_FOUND)
    find_package(embree 3 CONFIG QUIET)
    if(embree_FOUND AND TARGET embree)
      set(_ct_embree_target embree)
      set(_ct_embree_how "config ${embree_CONFIG}")
    endif()
  endif()

  if(NOT _ct_embree_target)
    find_path(CT_EMBREE_INCLUDE_DIR embree3/rtcore.h)
    find_library(CT_EMBREE_LIBRARY NAMES embree3)
    if(CT_EMBREE_INCLUDE_DIR AND CT_EMBREE_LIBRARY)
      if(NOT TARGET ct_embree3_imported)
        add_library(ct_embree3_imported UNKNOWN IMPORTED)
        set_target_properties(ct_embree3_imported PROPERTIES
          IMPORTED_LOCATION "${CT_EMBREE_LIBRARY}"
          INTERFACE_INCLUDE_DIRECTORIES "${CT_EMBREE_INCLUDE_DIR}")
      endif()
      set(_ct_embree_target ct_embree3_imported)
      set(_ct_embree_how "library ${CT_EMBREE_LIBRARY}")
    endif()
  endif()
endif()

if(_ct_embree_target)
  set(CT_HAVE_EMBREE ON)
  message(STATUS "Embree 3 baseline: enabled (${_ct_embree_how})")

  # Warning set for the host-side C++ (matches the project's, minus
  # -Wconversion/-Werror which are for the flight library).
  set(_ct_embree_warnings -Wall -Wextra -Wshadow)

  add_library(ct_embree_baseline STATIC ${CMAKE_CURRENT_LIST_DIR}/embree_baseline.cpp)
  target_include_directories(ct_embree_baseline PUBLIC ${CMAKE_CURRENT_LIST_DIR})
  target_link_libraries(ct_embree_baseline PUBLIC ${_ct_embree_target})
  target_compile_features(ct_embree_baseline PUBLIC cxx_std_17)
  target_compile_options(ct_embree_baseline PRIVATE ${_ct_embree_warnings})

  # The repo root is derived from this file's location (same as
  # PROJECT_SOURCE_DIR here, but robust if bench/ ever calls project()).
  get_filename_component(_ct_embree_root "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
  add_executable(test_embree_baseline ${_ct_embree_root}/tests/test_embree_baseline.cpp)
  target_include_directories(test_embree_baseline PRIVATE ${_ct_embree_root}/tests/kit)
  target_link_libraries(test_embree_baseline PRIVATE ct_embree_baseline)
  target_compile_options(test_embree_baseline PRIVATE ${_ct_embree_warnings})
  add_test(NAME test_embree_baseline COMMAND test_embree_baseline)
else()
  if(CT_WITH_EMBREE)
    message(STATUS "Embree 3 baseline: Embree 3 not found (Debian: libembree-dev); "
                   "benchmark runs without the Embree comparison")
  else()
    message(STATUS "Embree 3 baseline: disabled (CT_WITH_EMBREE=OFF)")
  endif()
endif()

unset(_ct_embree_target)
unset(_ct_embree_how)
unset(_ct_embree_warnings)
unset(_ct_embree_root)
