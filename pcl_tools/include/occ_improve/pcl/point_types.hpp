#pragma once
// A PCL point type that carries the per-ray results as fields, so pcl_viewer and downstream PCL code
// can colour or filter by them: x y z (the surface point), surface_depth [m], probability (of the
// surface voxel) and improvement (eq. 4 for the ray).
#include <pcl/point_types.h>
#include <pcl/register_point_struct.h>

namespace occ_improve {

// PCL_ADD_POINT4D expands to an anonymous union of anonymous structs, which clang's -Wpedantic flags in the
// header that expands it (ours), whatever -isystem says of PCL's: silenced here, for users' -Werror builds.
#if defined(__clang__)
#pragma clang diagnostic push
#pragma clang diagnostic ignored "-Wgnu-anonymous-struct"
#pragma clang diagnostic ignored "-Wnested-anon-types"
#endif
struct EIGEN_ALIGN16 PointImprovement {
  PCL_ADD_POINT4D;
  float surface_depth;
  float probability;
  float improvement;
  PCL_MAKE_ALIGNED_OPERATOR_NEW
};
#if defined(__clang__)
#pragma clang diagnostic pop
#endif

}  // namespace occ_improve

POINT_CLOUD_REGISTER_POINT_STRUCT(occ_improve::PointImprovement,
                                  (float, x, x)(float, y, y)(float, z, z)(float, surface_depth, surface_depth)(
                                      float, probability, probability)(float, improvement, improvement))
