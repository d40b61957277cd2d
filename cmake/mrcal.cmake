# Finds libmrcal (Debian: libmrcal-dev) for the camera models of `conetrace
# geoloc` and the camera tests; defines the interface target ct_mrcal.
# Debian's libmrcal-dev ships no .pc or CMake config: locate it directly.
find_path(CT_MRCAL_INCLUDE_DIR mrcal/mrcal.h)
find_library(CT_MRCAL_LIBRARY NAMES mrcal)
if(NOT CT_MRCAL_INCLUDE_DIR OR NOT CT_MRCAL_LIBRARY)
  message(FATAL_ERROR
    "conetrace host tools: missing dependency libmrcal (Debian: libmrcal-dev).\n"
    "Run scripts/deps.sh (or apt-get install libmrcal-dev).")
endif()
message(STATUS "conetrace camera deps: libmrcal (${CT_MRCAL_LIBRARY})")
add_library(ct_mrcal INTERFACE)
# SYSTEM: mrcal.h uses GNU empty structs and a flexible array member
target_include_directories(ct_mrcal SYSTEM INTERFACE ${CT_MRCAL_INCLUDE_DIR})
target_link_libraries(ct_mrcal INTERFACE ${CT_MRCAL_LIBRARY})
