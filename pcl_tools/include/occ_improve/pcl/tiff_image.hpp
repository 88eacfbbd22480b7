#pragma once
// Deprecated include path, kept for one release (CHANGELOG.md, 0.2): the TIFF readers need no PCL and
// moved to occ_improve::io; include "occ_improve/io/tiff.hpp" instead. Define
// OCC_IMPROVE_WARN_OLD_INCLUDES to be told where.
#ifdef OCC_IMPROVE_WARN_OLD_INCLUDES
#pragma message("occ_improve/pcl/tiff_image.hpp is deprecated: include occ_improve/io/tiff.hpp")
#endif
#include "occ_improve/io/tiff.hpp"
