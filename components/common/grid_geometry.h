#pragma once
// CopyGridGeometry(): where a grid lies, copied between the grid types of the stack. SLAM's
// OccupancyMap, the explorer's Grid, the simulator's GridMap, the viewer's GridImage, the log
// tools' grids and occupancy_grid_t all place row-major cells the same way: resolution_m, width
// and height in cells, and the corner of cell (0, 0) at (origin_x_m, origin_y_m).

namespace sarmap {
namespace common {

template <class From, class To>
void CopyGridGeometry(const From& from, To* to) {
  to->resolution_m = from.resolution_m;
  to->width = from.width;
  to->height = from.height;
  to->origin_x_m = from.origin_x_m;
  to->origin_y_m = from.origin_y_m;
}

}  // namespace common
}  // namespace sarmap
