// C ABI: library-level calls and the error channel.
#include <cstring>
#include <type_traits>
#include <string>

#include "capi/firewall.h"
#include "particlemesh/particlemesh.h"
#include "particlemesh/version.h"

namespace PM_NAMESPACE::capi {

namespace {
thread_local std::string last_error;
}

void set_error(const std::string& message) noexcept {
  try {
    last_error = message;
  } catch (...) {
    // Out of memory while recording the message: keep the previous one.
  }
}

void clear_error() noexcept { last_error.clear(); }

}  // namespace particlemesh::capi

extern "C" {

uint32_t pm_abi_version(void) { return PM_ABI_VERSION; }

const char* pm_version_string(void) { return PARTICLEMESH_VERSION_STRING; }

const char* pm_status_string(pm_status status) {
  // A C caller may pass any int. Read it as an integer: in C++ a pm_status holding a value
  // outside the enumerators' range is undefined behaviour (UBSan: "load of value 999").
  std::underlying_type_t<pm_status> raw;
  static_assert(sizeof raw == sizeof status);
  std::memcpy(&raw, &status, sizeof raw);
  return particlemesh::status_name(static_cast<particlemesh::Status>(raw));
}

const char* pm_last_error_message(void) { return particlemesh::capi::last_error.c_str(); }

}  // extern "C"
