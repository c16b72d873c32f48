// Internal: the exception firewall of the C ABI. Every extern "C" entry point runs its body
// through guarded(), which turns any exception into a status (run_guarded, shared with the
// PCL bridge) and a thread-local message.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <new>
#include <string>
#include <vector>

#include "particlemesh/core/c_guard.h"
#include "particlemesh/core/error.h"
#include "particlemesh/particlemesh.h"

namespace PM_NAMESPACE::capi {

void set_error(const std::string& message) noexcept;
void clear_error() noexcept;

/// Runs `body` through run_guarded (particlemesh/core/c_guard.h), the message of a failure
/// kept for pm_last_error_message().
template <class F>
pm_status guarded(F&& body) noexcept {
  clear_error();
  return run_guarded([](const std::string& message) noexcept { set_error(message); }, body);
}

/// Throw InvalidArgument naming `name` if p is NULL.
template <class T>
void require(const T* p, const char* name) {
  if (p == nullptr) throw Error(Status::InvalidArgument, std::string(name) + " is NULL");
}

/// *p, or InvalidArgument naming `name` if p is NULL.
template <class T>
T& deref(T* p, const char* name) {
  require(p, name);
  return *p;
}

/// Copy the first min(caller_size, sizeof(T)) bytes of a struct whose first member is
/// uint32_t struct_size: old callers with smaller structs keep working.
template <class T>
T read_versioned(const T* in, const T& defaults, const char* name, const std::vector<size_t>& pointer_fields);
template <class T>
void check_versioned(const T* out, const char* name);
template <class T>
void write_versioned(T* out, const T& value, const char* name);

/// What an _init function starts with: *out zeroed and its struct_size set. False for NULL.
template <class T>
bool reset_versioned(T* out) {
  if (out == nullptr) return false;
  *out = T{};
  out->struct_size = sizeof(T);
  return true;
}

/// The caller's options struct `*options` read with read_versioned, what it lacks (all of it
/// for NULL) from `init`'s defaults. Its progress and progress_user_data are pointer fields,
/// as are `more_pointer_fields` (offsets).
template <class T>
T read_options(const T* options, void (*init)(T*), std::vector<size_t> more_pointer_fields = {}) {
  T defaults;
  init(&defaults);
  more_pointer_fields.push_back(offsetof(T, progress));
  more_pointer_fields.push_back(offsetof(T, progress_user_data));
  return read_versioned(options, defaults, "options", more_pointer_fields);
}

}  // namespace particlemesh::capi

#include <algorithm>
#include <cstring>

namespace PM_NAMESPACE::capi {

template <class T>
T read_versioned(const T* in, const T& defaults, const char* name, const std::vector<size_t>& pointer_fields) {
  T out = defaults;
  if (in == nullptr) return out;
  const uint32_t size = in->struct_size;
  if (size < sizeof(uint32_t) || size > 4096)
    throw Error(Status::InvalidArgument,
                std::string(name) + "->struct_size is " + std::to_string(size) +
                    " (call the matching _init function first)");
  // A size that ends inside a pointer field would hand the library half of a caller's
  // pointer (the rest from the default): no version of a struct ever ended there.
  for (const size_t p : pointer_fields)
    if (size > p && size < p + sizeof(void*))
      throw Error(Status::InvalidArgument,
                  std::string(name) + "->struct_size is " + std::to_string(size) +
                      ", which ends inside a pointer field (call the matching _init function first)");
  std::memcpy(&out, in, std::min<size_t>(size, sizeof(T)));
  out.struct_size = sizeof(T);
  return out;
}

template <class T>
void check_versioned(const T* out, const char* name) {
  const uint32_t size = out->struct_size;
  if (size < sizeof(uint32_t) || size > 4096)
    throw Error(Status::InvalidArgument, std::string(name) + "->struct_size must be set to the "
                                             "struct's size, got " + std::to_string(size));
}

template <class T>
void write_versioned(T* out, const T& value, const char* name) {
  check_versioned(out, name);
  const uint32_t size = out->struct_size;
  std::memcpy(reinterpret_cast<char*>(out) + sizeof(uint32_t),
              reinterpret_cast<const char*>(&value) + sizeof(uint32_t),
              std::min<size_t>(size, sizeof(T)) - sizeof(uint32_t));
}

}  // namespace particlemesh::capi
