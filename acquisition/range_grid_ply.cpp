#include "acquisition/range_grid_ply.h"
