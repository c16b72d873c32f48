// Frame collections: one file that lists a simulation's frame files with their times, as
// ParaView reads them. A .pvd (VTK XML: <VTKFile type="Collection"><Collection> with one
// <DataSet timestep="..." file="..."/> per frame) or a .series (JSON, ParaView's file series:
// {"file-series-version": "1.0", "files": [{"name": "...", "time": ...}, ...]}). The command
// line meshes every frame of one (docs/simulations.md).
#pragma once

#include "particlemesh/core/config.h"

#include <string>
#include <vector>

#include "particlemesh/core/export.h"

namespace PM_NAMESPACE {

struct CollectionFrame {
  double time = 0;     ///< the frame's timestep
  std::string listed;  ///< its file as the collection names it
  std::string path;    ///< that file, joined to the collection's folder
};

/// Whether `path` names a frame collection (by its extension, any case: .pvd or .series).
PM_EXPORT bool is_frame_collection(const std::string& path);

/// The frames a collection lists, by ascending time (frame n is the n-th, from 0). Whether the
/// files exist is not checked here. Files are taken only from the collection's folder or below
/// it (no absolute path, no '..'; Windows' backslashes read as '/'), as a .pvtu's pieces.
/// @throws Error(IoError) when the file cannot be read, Error(FormatError) naming the file
/// and what is wrong: not a collection, an entry without a file or a finite time, a file
/// outside the folder, two entries at one time (a frame in several parts: list a .pvtu),
/// no entry.
PM_EXPORT std::vector<CollectionFrame> read_frame_collection(const std::string& path);

}  // namespace particlemesh
