#include "ebslam/slam/grid_map2f.h"

#include <cmath>
#include <stdexcept>

namespace ebslam {

GridMap2f::GridMap2f(int w, int h, double res, double ox, double oy, float value)
    : width(w), height(h), resolution_m(res), origin_x_m(ox), origin_y_m(oy) {
  if (w <= 0 || h <= 0) throw std::invalid_argument("GridMap2f: size must be positive");
  if (!(res > 0.0) || !std::isfinite(res)) {
    throw std::invalid_argument("GridMap2f: resolution must be positive and finite");
  }
  data.assign(static_cast<std::size_t>(w) * h + 1, value);
  data.back() = 0.0f;  // value outside the grid
  inv_resolution_ = 1.0 / res;
}

}  // namespace ebslam
