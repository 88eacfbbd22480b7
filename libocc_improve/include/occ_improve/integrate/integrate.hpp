#pragma once
// Bayesian insertion (eq. 2, CONVENTIONS 4-5): each valid point's truncated OPDF is added in log-odds to every
// column whose angular extent overlaps its +-k sigma box, along the whole ray in front of it.
//
// Documented approximations of this fast path (all bounded; tests/reference checks them):
//  - voxels behind a measurement whose |logit P_s| < kSkipEpsilon (1e-6) are not updated (CONVENTIONS 4); where
//    the angular term B >= log(8 / (3 eps)) = 14.8 (a pixel-native return's diagonal neighbours, B = 24)
//    the peak term is below eps/8 at every depth, so the update ends where the step term's deviation from
//    1/2 falls below eps/8: (log(4/eps) - 4 - B)/2 sigmas (-6.4 at B = 24), in front of the return;
//  - logit P_s is evaluated in float with polynomial exp/log (fast_math.hpp; |error| < 2e-6 against the
//    double logit_opdf, tests/test_fast_math.cpp);
//  - exact mode: far in front (u < -20) logit P_s is taken as log(1/2) + u (error < 1e-8);
//  - clamped mode skips voxels whose result is known without evaluating logit P_s (exact under clamping):
//    a) logit P_s <= 0 wherever t = (rho - rho_bar)/sigma <= -1.5, for every B >= 0, so the leading run
//       of L_min voxels is left alone there;
//    b) for t <= -3 - B/2, logit P_s <= log(1/2) + u + 0.072, so an untouched voxel (L = 0) with
//       log(1/2) + u <= L_min - 0.2 ends at L_min;
//    b') for B >= 15 (a pixel-native return's diagonal neighbours, B = 24) |logit P_s| < 4.5e-7 wherever
//       t > -1.5, so a column whose leading L_min run reaches t = -1.5 is not updated at all (a) + CONVENTIONS 4);
//    b'') per column and call (per part of at most 1024 measurements where a tile receives more), below
//       the depth where every measurement of the call has t <= -1.5 (so logit P_s <= 0 for all of them)
//       and one of them alone satisfies b), a voxel holding L <= 0 ends the call at L_min whatever the
//       order (clamped sums of non-positive terms): the leading run takes such voxels before any
//       measurement is applied, so a neighbour's update that lies wholly in front
//       of the column's own return costs O(1) (tests: Integrate.FreeSpaceOfACall*);
//    c) while a column is being updated, the bins the call's measurements reach hold odds e^L (one exp
//       and one log per voxel and call instead of a log per voxel and measurement); the clamps map to
//       L_min/L_max exactly and the round trip moves other voxels by < 5e-7 + 2e-7 |L| (once per column
//       and call: a column is loaded once, receives all its measurements of the call, and is stored
//       once). Bins no measurement of the call reaches stay in log-odds and are stored bit for bit
//       (Integrate.BinsNoMeasurementOfACallReachesAreStoredBitForBit).
#include "occ_improve/grid/grid.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sensor/sensor_model.hpp"
#include "occ_improve/maps/surface.hpp"

#include <Eigen/Core>
#include <cstddef>
#include <vector>

namespace occ_improve {

constexpr double kSkipEpsilon = 1e-6;

/// A view of xyz points in the sensor frame: `count` points, the i-th at xyz[i * stride_floats].
/// stride_floats = 3 for packed xyz and Eigen::Matrix3Xf, 4 for PCL's PointXYZ, 8 for PointXYZRGB...
struct PointSpan {
  const float* xyz = nullptr;
  std::size_t count = 0;
  std::size_t stride_floats = 3;

  static PointSpan from(const std::vector<Eigen::Vector3f>& points);
  static PointSpan from(const Eigen::Matrix3Xf& points);
};

/// An organized depth image: z-depth in metres per pixel (0 or NaN = no return), row-major.
struct DepthImage {
  const float* depth_m = nullptr;
  std::size_t pixel_count = 0;  ///< must equal intrinsics.width * intrinsics.height
  PinholeIntrinsics intrinsics;
};

struct InsertionOptions {
  /// More threads than this is a mistake (the tools' -threads has the same bound), not a request.
  static constexpr int kMaxThreads = 1024;
  /// 0: std::thread::hardware_concurrency(); 1: single-threaded; at most kMaxThreads. The work is split in
  /// this many parts (the result does not depend on it), run by the calling thread and the process's pool
  /// of workers, which keeps at most one per core beside the caller between calls.
  int threads = 0;
  void validate() const;  ///< threads outside [0, kMaxThreads] -> InvalidParameter
};

/// What happened to every point handed in: received = inserted + skipped_invalid + skipped_outside_fov
/// + skipped_masked.
struct InsertionReport {
  std::size_t points_received = 0;
  std::size_t points_inserted = 0;
  std::size_t skipped_invalid = 0;      ///< NaN/Inf coordinate or rho == 0 (no return)
  std::size_t skipped_outside_fov = 0;  ///< direction outside the grid's angular range
  std::size_t skipped_masked = 0;       ///< valid, on a ray a Mapper's column mask leaves out (Mapper only)
  std::size_t beyond_depth_range = 0;   ///< inserted; only their free space lies in the grid
  /// inserted with a range below the depth range's start: their OPDF lies in front of the grid, so little
  /// or nothing of them is kept (millimetres given as metres, or a sensor nearer than the preset's minimum)
  std::size_t nearer_than_depth_range = 0;
  std::size_t column_updates = 0;       ///< (measurement, column) pairs applied
  double seconds = 0.0;

  InsertionReport& operator+=(const InsertionReport& other);
};

/// Inserts points (sensor frame). Skips and counts invalid and out-of-field points; never throws for
/// individual points. Deterministic: every column receives its measurements in input order.
/// The calling thread keeps its working buffers between calls (about 40 bytes per point of the largest
/// call, and 64 depth rows of floats per worker thread), so a stream of frames allocates them once.
InsertionReport insert_points(ColumnGrid& grid, const SensorModel& model, PointSpan points,
                              const InsertionOptions& options = {});

/// insert_points that also keeps `surface` (of this grid) current: each column the call updates gets its
/// surface recomputed right after its voxels, while they are still in cache, instead of in a separate
/// update_surface pass. Returns the columns whose surface changed (any order), as update_surface would
/// for the updated columns. The grid's changed-column record is kept as by insert_points.
/// Throws InvalidInput when `surface` is not the grid's size.
InsertionReport insert_points(ColumnGrid& grid, const SensorModel& model, PointSpan points, SurfaceMap& surface,
                              std::vector<ColumnIndex>& surface_changed, const InsertionOptions& options = {});

/// Throws InvalidParameter naming both cameras when the grid was built for a camera (pinhole columns, or a
/// spherical grid's observable columns) and `intrinsics` describe another one (same_camera): its pixels
/// would land in other columns or outside the field of view and be dropped without a word.
void require_grid_camera(const GridGeometry& geometry, const PinholeIntrinsics& intrinsics);

/// Back-projects an organized depth image through its intrinsics and inserts it.
/// Throws InvalidInput when the buffer is null or its size does not match the intrinsics, and as
/// require_grid_camera when the image is from another camera than the grid's.
InsertionReport insert_depth_image(ColumnGrid& grid, const SensorModel& model, const DepthImage& image,
                                   const InsertionOptions& options = {});

/// Back-projection used by insert_depth_image (pixels with no return give NaN points, kept in place).
std::vector<Eigen::Vector3f> depth_image_to_points(const DepthImage& image);

/// Inserts several frames of the same viewpoint in order and sums their reports.
InsertionReport insert_frames(ColumnGrid& grid, const SensorModel& model, const std::vector<PointSpan>& frames,
                              const InsertionOptions& options = {});

/// logit P_s for a run of depth bins of one column, as the fast path evaluates it (exposed for tests).
/// out[i] = logit P_s at depth centres[i], for a measurement at rho_bar with angular term B.
void logit_opdf_profile(const double* centres, std::size_t n, double rho_bar, double angular_term, double sigma_rho,
                        float* out);

}  // namespace occ_improve
