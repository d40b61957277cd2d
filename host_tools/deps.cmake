# Finds OpenImageIO, libgeotiff and libtiff; defines the interface target
# ct_host_deps.  (Owned by the DEM I/O work; keep the target name.)
find_package(Threads REQUIRED)
add_library(ct_host_deps INTERFACE)
