#pragma once
// Deprecated include path, kept for one release (CHANGELOG.md, 0.2): include
// "occ_improve/sensor/intrinsics_fit.hpp" instead. Define OCC_IMPROVE_WARN_OLD_INCLUDES to be told where.
#ifdef OCC_IMPROVE_WARN_OLD_INCLUDES
#pragma message("occ_improve/intrinsics_fit.hpp is deprecated: include occ_improve/sensor/intrinsics_fit.hpp")
#endif
#include "occ_improve/sensor/intrinsics_fit.hpp"
