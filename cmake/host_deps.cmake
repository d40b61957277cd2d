# Finds OpenImageIO, libgeotiff and libtiff; defines the interface target
# ct_host_deps.  (Owned by the DEM I/O work; keep the target name.)
#
# Note: Debian 12's OpenImageIOConfig.cmake is not usable as shipped: its
# exported targets reference the command-line tools (/usr/bin/iconvert, ...)
# which live in the separate openimageio-tools package, and Imath's targets
# reference the Python bindings, so find_package(OpenImageIO CONFIG) aborts
# configure with a FATAL_ERROR when those packages are absent.  We therefore
# locate the headers and libraries directly (as the .pc file does).
# libgeotiff 1.7 on Debian ships neither a CMake config nor a .pc file.

find_package(Threads REQUIRED)

set(_ct_missing "")

# --- OpenImageIO (pixels) ---------------------------------------------------
find_path(CT_OIIO_INCLUDE_DIR OpenImageIO/imageio.h)
find_library(CT_OIIO_LIBRARY NAMES OpenImageIO)
find_library(CT_OIIO_UTIL_LIBRARY NAMES OpenImageIO_Util)
if(NOT CT_OIIO_INCLUDE_DIR OR NOT CT_OIIO_LIBRARY OR NOT CT_OIIO_UTIL_LIBRARY)
  list(APPEND _ct_missing "OpenImageIO (Debian: libopenimageio-dev)")
else()
  file(STRINGS "${CT_OIIO_INCLUDE_DIR}/OpenImageIO/oiioversion.h" _ct_oiio_ver
       REGEX "^#define OIIO_VERSION_(MAJOR|MINOR|PATCH) ")
  string(REGEX REPLACE ".*MAJOR ([0-9]+).*MINOR ([0-9]+).*PATCH ([0-9]+).*" "\\1.\\2.\\3"
         CT_OIIO_VERSION "${_ct_oiio_ver}")
  if(CT_OIIO_VERSION VERSION_LESS 2.2)
    list(APPEND _ct_missing "OpenImageIO >= 2.2 (found ${CT_OIIO_VERSION})")
  endif()
endif()

# --- libtiff -----------------------------------------------------------------
find_package(TIFF QUIET)
if(NOT TIFF_FOUND)
  list(APPEND _ct_missing "libtiff (Debian: libtiff-dev)")
endif()

# --- libgeotiff ----------------------------------------------------------------
find_path(CT_GEOTIFF_INCLUDE_DIR geotiffio.h PATH_SUFFIXES geotiff libgeotiff)
find_library(CT_GEOTIFF_LIBRARY NAMES geotiff geotiff_i)
if(NOT CT_GEOTIFF_INCLUDE_DIR OR NOT CT_GEOTIFF_LIBRARY)
  list(APPEND _ct_missing "libgeotiff (Debian: libgeotiff-dev)")
endif()

if(_ct_missing)
  string(REPLACE ";" ", " _ct_missing_str "${_ct_missing}")
  message(FATAL_ERROR
    "conetrace host tools: missing dependencies: ${_ct_missing_str}.\n"
    "Run scripts/deps.sh (or apt-get install libopenimageio-dev libgeotiff-dev libtiff-dev).")
endif()

message(STATUS "conetrace host deps: OpenImageIO ${CT_OIIO_VERSION} (${CT_OIIO_LIBRARY}), "
               "libtiff ${TIFF_VERSION_STRING}, libgeotiff (${CT_GEOTIFF_LIBRARY})")

add_library(ct_host_deps INTERFACE)
target_include_directories(ct_host_deps SYSTEM INTERFACE
  ${CT_OIIO_INCLUDE_DIR} ${CT_GEOTIFF_INCLUDE_DIR})
target_link_libraries(ct_host_deps INTERFACE
  ${CT_OIIO_LIBRARY} ${CT_OIIO_UTIL_LIBRARY}
  ${CT_GEOTIFF_LIBRARY} TIFF::TIFF Threads::Threads)
