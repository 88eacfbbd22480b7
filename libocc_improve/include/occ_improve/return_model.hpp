#pragma once
// Deprecated include path, kept for one release (CHANGELOG.md, 0.2): include
// "occ_improve/planning/return_model.hpp" instead. Define OCC_IMPROVE_WARN_OLD_INCLUDES to be told where.
#ifdef OCC_IMPROVE_WARN_OLD_INCLUDES
#pragma message("occ_improve/return_model.hpp is deprecated: include occ_improve/planning/return_model.hpp")
#endif
#include "occ_improve/planning/return_model.hpp"
