// The spacing estimate moved to particlemesh/spatial/spacing.h (spacing is a property of a
// cloud, used by the triangulation and the implicit surfaces alike); this header is kept so
// that code including the old path still compiles.
#pragma once

#include "particlemesh/spatial/spacing.h"
