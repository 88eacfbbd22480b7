#pragma once
// A pinhole camera from its 3 x 3 matrix K, as intrinsics files (7-Scenes, 3DMatch), Open3D and numpy give
// it: one rule for the tools' files and Python's intrinsics_from_matrix.
#include "occ_improve/geometry/geometry.hpp"

#include <array>

namespace occ_improve {

/// PinholeIntrinsics from K = [fx 0 cx; 0 fy cy; 0 0 1] given row by row, and the image size (K holds
/// none). Throws InvalidInput for a skew or another last row (the library's pinhole has neither), naming a
/// transposed K (cx, cy in the last row: MATLAB's convention, which read as cx = cy = 0), and
/// InvalidParameter for values PinholeIntrinsics::validate refuses.
PinholeIntrinsics intrinsics_from_matrix(const std::array<double, 9>& k_row_major, int width, int height);

}  // namespace occ_improve
