// The exception firewall of a C ABI: what every extern "C" entry point of libparticlemesh and
// of the PCL bridge runs its body through, so that no exception crosses into C and every
// failure maps to the same pm_status with a one-line message.
#pragma once

#include "particlemesh/core/config.h"

#include <exception>
#include <new>
#include <stdexcept>
#include <string>

#include "particlemesh/core/error.h"
#include "particlemesh/particlemesh.h"

namespace PM_NAMESPACE {

/// Runs `body()`: PM_OK when it returns; when it throws, hands the message to
/// `report(const std::string&)` (which must not throw) and returns the status:
/// particlemesh::Error: its own status and message; std::bad_alloc and std::length_error (a
/// size beyond what can be allocated): PM_STATUS_OUT_OF_MEMORY; any other exception:
/// PM_STATUS_INTERNAL, "internal error: ...".
template <class Report, class Body>
pm_status run_guarded(Report&& report, Body&& body) noexcept {
  try {
    body();
    return PM_OK;
  } catch (const Error& e) {
    report(std::string(e.what()));
    return static_cast<pm_status>(e.status());
  } catch (const std::bad_alloc&) {
    report(std::string("out of memory"));
    return PM_STATUS_OUT_OF_MEMORY;
  } catch (const std::length_error&) {
    report(std::string("out of memory (a size exceeded what can be allocated)"));
    return PM_STATUS_OUT_OF_MEMORY;
  } catch (const std::exception& e) {
    report(std::string("internal error: ") + e.what());
    return PM_STATUS_INTERNAL;
  } catch (...) {
    report(std::string("internal error: unknown exception"));
    return PM_STATUS_INTERNAL;
  }
}

}  // namespace particlemesh
