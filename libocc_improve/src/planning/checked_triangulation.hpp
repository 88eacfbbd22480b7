#pragma once
// Internal: the triangulation without its checks, for a caller that has made them (predict_dense_depth
// checks the sparse image once for the distance transform and the triangulation).
#include "occ_improve/planning/sample_triangulation.hpp"

namespace occ_improve::detail {

/// triangulate_samples for valid params and an image that check_sparse_depth_image has passed.
SampleTriangulation triangulate_checked_samples(const std::vector<float>& sparse_depth_m, int width, int height,
                                                const SensorModel& model, const TriangulationParams& params);

}  // namespace occ_improve::detail
