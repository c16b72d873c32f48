// The namespace of the C++ API, versioned.
//
// Every C++ name of the library lives in an inline namespace inside `particlemesh`
// (OpenSubdiv's habit, with C++11's inline namespaces): callers write particlemesh::Vec3, while
// the symbols carry the version (particlemesh::v1::...), so two builds of different versions
// linked into one host process (two plug-ins, say) do not bind to each other's functions.
// The C ABI (particlemesh.h, pm_*) is unversioned: its compatibility is kept by struct_size.
#pragma once

/// The inline namespace's name; raised with every incompatible change of the C++ API.
#define PM_INLINE_NAMESPACE v1

/// What the library's headers and sources open: `namespace PM_NAMESPACE { ... }` is
/// `namespace particlemesh { inline namespace v1 { ... } }`.
#define PM_NAMESPACE particlemesh::inline PM_INLINE_NAMESPACE
