// Progress reporting and cancellation for long calls.
#pragma once

#include "particlemesh/core/config.h"

#include <functional>
#include <string_view>

namespace PM_NAMESPACE {

/// Called with the name of the running stage and the overall fraction done (0..1).
/// Return false to cancel: the call then throws Error(Status::Cancelled) promptly and
/// leaves its outputs untouched. It is only ever called on the thread that started the
/// call, at most about every 50 ms plus once per stage.
using ProgressCallback = std::function<bool(std::string_view stage, double fraction)>;

}  // namespace particlemesh
