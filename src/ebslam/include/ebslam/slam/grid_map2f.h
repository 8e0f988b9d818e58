#pragma once

// The float grid over the ceiling plane that EB-PF localises against and EB-SLAM-2D maps into.

#include <cstddef>
#include <vector>

namespace ebslam {

/// Dense float grid on the ceiling plane. Cell (row r, column c) covers world x in
/// [origin_x + c res, origin_x + (c+1) res) and y in [origin_y + r res, origin_y + (r+1) res).
/// `data` holds the width * height cells row by row plus one trailing 0, the value returned for
/// points outside the grid (lets the particle loop look up without branches).
struct GridMap2f {
  int width = 0;
  int height = 0;
  double resolution_m = 0.0;
  double origin_x_m = 0.0;
  double origin_y_m = 0.0;
  std::vector<float> data;

  GridMap2f() = default;
  /// Throws std::invalid_argument for non-positive sizes or resolution.
  GridMap2f(int width, int height, double resolution_m, double origin_x_m, double origin_y_m,
            float value = 0.0f);

  float& at(int col, int row) { return data[static_cast<std::size_t>(row) * width + col]; }
  float at(int col, int row) const { return data[static_cast<std::size_t>(row) * width + col]; }
  /// Value of the cell containing world point (x, y); 0 outside the grid.
  float lookup(double x, double y) const {
    const double fc = (x - origin_x_m) * inv_resolution_;
    const double fr = (y - origin_y_m) * inv_resolution_;
    if (!(fc >= 0.0 && fr >= 0.0 && fc < width && fr < height)) return 0.0f;  // outside
    return data[static_cast<std::size_t>(fr) * width + static_cast<std::size_t>(fc)];
  }
  double invResolution() const { return inv_resolution_; }
  std::size_t cellCount() const { return static_cast<std::size_t>(width) * height; }

 private:
  double inv_resolution_ = 0.0;
};

}  // namespace ebslam
