// placeholder, being written
#include "dem_io.hpp"
