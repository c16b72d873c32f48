// Symbol visibility for the particlemesh shared library.
#pragma once

#if defined(_WIN32)
#  if defined(PARTICLEMESH_BUILDING)
#    define PM_EXPORT __declspec(dllexport)
#  else
#    define PM_EXPORT __declspec(dllimport)
#  endif
#else
#  define PM_EXPORT __attribute__((visibility("default")))
#endif
