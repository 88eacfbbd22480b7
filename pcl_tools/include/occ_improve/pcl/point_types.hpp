#pragma once
// A PCL point type that carries the per-ray results as fields, so pcl_viewer and downstream PCL code
// can colour or filter by them: x y z (the surface point), surface_depth [m], probability (of the
// surface voxel) and improvement (eq. 4 for the ray).
#include <pcl/point_types.h>
#include <pcl/register_point_struct.h>

namespace occ_improve {

struct EIGEN_ALIGN16 PointImprovement {
  PCL_ADD_POINT4D;
  float surface_depth;
  float probability;
  float improvement;
  PCL_MAKE_ALIGNED_OPERATOR_NEW
};

}  // namespace occ_improve

POINT_CLOUD_REGISTER_POINT_STRUCT(occ_improve::PointImprovement,
                                  (float, x, x)(float, y, y)(float, z, z)(float, surface_depth, surface_depth)(
                                      float, probability, probability)(float, improvement, improvement))
