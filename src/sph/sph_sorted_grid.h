// The SPH solver's neighbour search (thesis 8.1.1) is the core's sorted cell grid.
#pragma once

#include "relaxed_connectivity/core/sorted_cell_grid.h"

namespace rc {

using SphSortedGrid = SortedCellGrid;

}  // namespace rc
