#pragma once
// Deprecated include path, kept for one release (CHANGELOG.md, 0.2): include
// "occ_improve/planning/ranking.hpp" instead. Define OCC_IMPROVE_WARN_OLD_INCLUDES to be told where.
#ifdef OCC_IMPROVE_WARN_OLD_INCLUDES
#pragma message("occ_improve/ranking.hpp is deprecated: include occ_improve/planning/ranking.hpp")
#endif
#include "occ_improve/planning/ranking.hpp"
