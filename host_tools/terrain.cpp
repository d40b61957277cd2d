// placeholder, being written
#include "terrain.hpp"
