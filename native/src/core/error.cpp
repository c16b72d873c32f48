#include "particlemesh/core/error.h"

namespace PM_NAMESPACE {

const char* status_name(Status status) noexcept {
  switch (status) {
    case Status::Ok: return "ok";
    case Status::InvalidArgument: return "invalid argument";
    case Status::InvalidInput: return "invalid input";
    case Status::IoError: return "i/o error";
    case Status::FormatError: return "format error";
    case Status::OutOfMemory: return "out of memory";
    case Status::Cancelled: return "cancelled";
    case Status::LimitExceeded: return "limit exceeded";
    case Status::Internal: return "internal error";
  }
  return "unknown status";
}

}  // namespace particlemesh
