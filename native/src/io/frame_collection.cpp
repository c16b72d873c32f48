#include "particlemesh/io/frame_collection.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string_view>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/file_reader.h"
#include "io/formats.h"
#include "io/text_numbers.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE {

namespace detail {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& problem) {
  throw Error(Status::FormatError, "'" + path + "': " + problem);
}

/// A .series: ParaView's JSON file series. Parsed with nlohmann/json (the CLI's JSON library,
/// header-only); only "files" is read, each entry's "name" and "time".
std::vector<std::pair<double, std::string>> read_series(const std::string& path) {
  const std::string text = FileReader(path).read_rest();
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    fail(path, std::string("not a JSON file series (") + e.what() + ")");
  }
  if (!doc.is_object() || !doc.contains("files") || !doc["files"].is_array())
    fail(path, "not a file series: no \"files\" list (a .series holds {\"file-series-version\": \"1.0\", "
               "\"files\": [{\"name\": ..., \"time\": ...}, ...]})");
  std::vector<std::pair<double, std::string>> out;
  for (const auto& f : doc["files"]) {
    const std::string label = "files[" + std::to_string(out.size()) + "]";
    if (!f.is_object() || !f.contains("name") || !f["name"].is_string() || f["name"].get<std::string>().empty())
      fail(path, label + " has no \"name\"");
    const std::string name = f["name"].get<std::string>();
    if (!f.contains("time") || !f["time"].is_number())
      fail(path, label + " ('" + shown(name) + "') has no numeric \"time\"");
    out.emplace_back(f["time"].get<double>(), name);
  }
  return out;
}

std::string time_text(double t) {
  char b[32];
  std::snprintf(b, sizeof b, "%.17g", t);
  return b;
}

}  // namespace

}  // namespace detail

bool is_frame_collection(const std::string& path) {
  const std::string e = detail::lower_extension(path);
  return e == ".pvd" || e == ".series";
}

std::vector<CollectionFrame> read_frame_collection(const std::string& path) {
  std::vector<std::pair<double, std::string>> entries;
  if (detail::lower_extension(path) == ".series") {
    entries = detail::read_series(path);
  } else {
    for (const auto& [time, file] : detail::read_pvd_entries(path)) {
      double t = 0;
      std::string_view text = time;
      while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
      while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
      if (detail::parse_number(text, t) != detail::NumberText::Ok)
        detail::fail(path, "the timestep '" + detail::shown(time) + "' of '" + detail::shown(file) +
                               "' is not a number");
      entries.emplace_back(t, file);
    }
  }
  if (entries.empty()) detail::fail(path, "the collection lists no frame");
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  std::vector<CollectionFrame> frames;
  for (auto& [time, file] : entries) {
    if (!std::isfinite(time)) detail::fail(path, "the time of '" + detail::shown(file) + "' is not finite");
    std::string portable;
    if (!detail::path_inside_folder(file, portable))
      detail::fail(path, "the frame '" + detail::shown(file) +
                             "' is not a path inside the collection's folder (frames are read only from beside it or "
                             "below it)");
    frames.push_back({time, file, (folder / portable).string()});
  }
  std::stable_sort(frames.begin(), frames.end(), [](const auto& a, const auto& b) { return a.time < b.time; });
  for (size_t i = 1; i < frames.size(); ++i)
    if (frames[i].time == frames[i - 1].time)
      detail::fail(path, "'" + detail::shown(frames[i - 1].listed) + "' and '" + detail::shown(frames[i].listed) +
                             "' share the time " + detail::time_text(frames[i].time) +
                             " (one file per frame: a frame in several parts is read from a .pvtu or .pvtp listing "
                             "them)");
  return frames;
}

}  // namespace particlemesh
