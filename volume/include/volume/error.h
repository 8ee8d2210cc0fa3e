// Moved to core/error.h, where Error carries a kind. This header only forwards, for
// branches that still include it; new code includes "core/error.h".
#pragma once

#include "core/error.h"
