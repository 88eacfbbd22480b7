#pragma once
// The slow, obviously-correct reference of eqs. 1, 2 and the surface (CONVENTIONS 3-6): a dense grid of
// log-odds in double, every voxel of every column in the angular window updated with eq. 1 evaluated
// in long double, no depth truncation, no tables, no threads. The fast path is checked against it.
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/grid/grid.hpp"
#include "occ_improve/maps/surface.hpp"
#include "occ_improve/sensor/sensor_model.hpp"

#include <Eigen/Core>
#include <vector>

namespace occ_improve::reference {

/// logit of eq. 1, straight from its definition (log-sum-exp in long double).
long double logit_opdf(long double d_rho, long double angular_term, long double sigma_rho);

class DenseGrid {
public:
  DenseGrid(const GridGeometry& geometry, const SensorModel& model, const GridOptions& options);
  /// Inserts points in order (NaN/zero and out-of-field points are skipped, as CONVENTIONS 1 says).
  void insert(const std::vector<Eigen::Vector3f>& points);
  double log_odds(std::size_t column, int bin) const { return values_[column * bins_ + static_cast<std::size_t>(bin)]; }
  /// Starts a voxel from a given state (a map made elsewhere), before any insert.
  void set_log_odds(std::size_t column, int bin, double value) {
    values_[column * bins_ + static_cast<std::size_t>(bin)] = value;
    touched_[column] = 1;
  }
  bool touched(std::size_t column) const { return touched_[column] != 0; }
  const GridGeometry& geometry() const { return geometry_; }
  const SensorModel& model() const { return model_; }

  struct Surface {
    double depth_m = 0, probability = 0.5;
    int bin = -1;
    bool unknown = true;
  };
  /// CONVENTIONS 6 by brute force over the dense column.
  Surface surface(std::size_t column) const;

private:
  GridGeometry geometry_;
  SensorModel model_;
  GridOptions options_;
  std::size_t bins_;
  double lmin_, lmax_;
  std::vector<double> values_;
  std::vector<unsigned char> touched_;
};

/// Eqs. 3-4 (CONVENTIONS 7) by brute force in double for every column, over the given surfaces (one per column):
/// the window is found by testing every column's extent against the +-k sigma box of the simulated
/// measurement; unknown surfaces take part with depth 0 and P = 1/2; P_s comes from logit_opdf above.
std::vector<double> improvement_map(const GridGeometry& geometry, const SensorModel& model,
                                    const std::vector<DenseGrid::Surface>& surfaces);
/// The same over the dense grid's own surface.
std::vector<double> improvement_map(const DenseGrid& grid);

/// The fast path's surface map as the reference's per-column surfaces (improvement_map's input).
std::vector<DenseGrid::Surface> surfaces_of(const SurfaceMap& surface);

/// The fast improvement map (compute_improvement) against improvement_map, both over `surface`.
struct ImprovementAgreement {
  double max_difference = 0;      ///< largest |fast - reference| over the columns
  double max_abs_reference = 0;   ///< largest |reference|: a flat map would agree trivially
};
ImprovementAgreement compare_improvement(const GridGeometry& geometry, const SensorModel& model,
                                         const SurfaceMap& surface);

/// The fast grid's surface (compute_surface) against the reference's, column by column.
struct SurfaceAgreement {
  std::size_t columns = 0, same_bin = 0, touched = 0;  ///< touched: columns the reference knows
  double max_dp = 0;                                   ///< largest surface probability difference
};
SurfaceAgreement compare_surfaces(const ColumnGrid& fast, const DenseGrid& ref);

/// Largest |fast - reference| log-odds over every voxel of the grid (clamped mode: exact-mode log-odds
/// reach -1e3, where float sums and doubles differ by more than the tests' 1e-4).
double max_log_odds_difference(const ColumnGrid& fast, const DenseGrid& ref);

/// A geometry covering only a window of another one's columns, with identical column extents:
/// columns [azimuth_first, azimuth_first + width) x [elevation_first, elevation_first + height).
GridGeometry crop(const GridGeometry& full, int azimuth_first, int elevation_first, int width, int height);

}  // namespace occ_improve::reference
