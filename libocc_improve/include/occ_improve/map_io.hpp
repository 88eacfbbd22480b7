#pragma once
// Deprecated include path, kept for one release (CHANGELOG.md, 0.2): include
// "occ_improve/io/map_io.hpp" instead. Define OCC_IMPROVE_WARN_OLD_INCLUDES to be told where.
#ifdef OCC_IMPROVE_WARN_OLD_INCLUDES
#pragma message("occ_improve/map_io.hpp is deprecated: include occ_improve/io/map_io.hpp")
#endif
#include "occ_improve/io/map_io.hpp"
