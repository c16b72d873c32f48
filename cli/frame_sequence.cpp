#include "frame_sequence.h"

#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <new>
#include <sstream>
#include <thread>
#include <sys/stat.h>
#include <unistd.h>

#include "commands.h"
#include "particlemesh/core/error.h"
#include "attribute_selection.h"
#include "particlemesh/version.h"
#include "progress_line.h"

namespace particlemesh::cli {

namespace {

std::string folder_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string(".") : slash == 0 ? std::string("/") : path.substr(0, slash);
}

std::string name_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

/// Modification time in nanoseconds; false when `path` is not a regular file.
bool modified_ns(const std::string& path, int64_t& ns) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return false;
  ns = int64_t(st.st_mtim.tv_sec) * 1000000000 + int64_t(st.st_mtim.tv_nsec);
  return true;
}

bool regular_file(const std::string& path) {
  int64_t ns;
  return modified_ns(path, ns);
}

std::string file_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

bool parse_int(std::string_view s, int64_t& v) {
  if (s.empty()) return false;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

/// "A:B" (inclusive) or "N".
std::pair<int64_t, int64_t> parse_frames(const std::string& text) {
  const size_t colon = text.find(':');
  int64_t a = 0, b = 0;
  const bool ok = colon == std::string::npos
                      ? parse_int(text, a) && (b = a, true)
                      : parse_int(std::string_view(text).substr(0, colon), a) &&
                            parse_int(std::string_view(text).substr(colon + 1), b);
  if (!ok) throw UsageError("--frames '" + text + "': expected FIRST:LAST (inclusive, e.g. 10:250) or one frame number");
  if (a > b) throw UsageError("--frames '" + text + "': the first frame is after the last");
  return {a, b};
}

std::string seconds_text(double s) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f s", s);
  return b;
}

/// Frame numbers as "3, 7, 9 and 4 more".
std::string frame_list(const std::vector<int64_t>& frames, size_t total) {
  std::string t;
  for (size_t i = 0; i < frames.size(); ++i) t += (i ? ", " : "") + std::to_string(frames[i]);
  if (total > frames.size()) t += " and " + std::to_string(total - frames.size()) + " more";
  return t;
}

}  // namespace

bool has_frame_field(const std::string& path) { return path.find_first_of("{}") != std::string::npos; }

bool is_sequence_collection(const std::string& path) { return !has_frame_field(path) && is_frame_collection(path); }

bool is_sequence_input(const std::string& path) { return has_frame_field(path) || is_frame_collection(path); }

FramePattern parse_frame_pattern(const std::string& path, const std::string& option) {
  auto bad = [&](const std::string& why) {
    throw UsageError(option + " '" + path + "': " + why +
                     " (a frame pattern holds one field: {} or a zero-padded {:04d}, e.g. sim/fluid_{:04d}.vtk)");
  };
  const size_t open = path.find('{');
  const size_t close = path.find('}');
  if (open == std::string::npos || close == std::string::npos || close < open) bad("no frame field");
  if (path.find_first_of("{}", close + 1) != std::string::npos) bad("more than one frame field, or a stray brace");
  const std::string spec = path.substr(open + 1, close - open - 1);
  FramePattern p;
  p.prefix = path.substr(0, open);
  p.suffix = path.substr(close + 1);
  p.text = path;
  if (spec.empty() || spec == ":d") return p;
  // ":0N" or ":0Nd", N = 1..18.
  std::string digits = spec.size() > 2 && spec[0] == ':' && spec[1] == '0' ? spec.substr(2) : std::string();
  if (!digits.empty() && digits.back() == 'd') digits.pop_back();
  int64_t width = 0;
  if (!parse_int(digits, width) || width < 1 || width > 18 || digits[0] == '-' || digits[0] == '+')
    bad("unsupported field '{" + spec + "}'");
  p.width = int(width);
  return p;
}

std::string frame_path(const FramePattern& p, int64_t frame) {
  std::string digits = std::to_string(frame < 0 ? -(frame + 1) + uint64_t(1) : uint64_t(frame));
  const std::string sign = frame < 0 ? "-" : "";
  const size_t width = size_t(p.width);
  if (sign.size() + digits.size() < width) digits.insert(0, width - sign.size() - digits.size(), '0');
  return p.prefix + sign + digits + p.suffix;
}

std::vector<int64_t> find_frames(const FramePattern& p) {
  // The field's folder is listed; a name there that starts like the pattern and goes on with
  // a number is frame n when the pattern written for n gives exactly that file. ("x" stands
  // in for the field, so that a prefix ending in '/' splits into its folder and no name.)
  const std::string folder = folder_of(p.prefix + "x");
  const std::string lead = name_of(p.prefix + "x");
  const std::string name_prefix = lead.substr(0, lead.size() - 1);
  std::vector<int64_t> frames;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.compare(0, name_prefix.size(), name_prefix) != 0) continue;
    size_t end = name_prefix.size();
    if (end < name.size() && name[end] == '-') ++end;
    while (end < name.size() && name[end] >= '0' && name[end] <= '9') ++end;
    const std::string number = name.substr(name_prefix.size(), end - name_prefix.size());
    int64_t n = 0;
    if (!parse_int(number, n)) continue;
    FramePattern field;
    field.width = p.width;
    if (frame_path(field, n) == number && regular_file(frame_path(p, n)))
      frames.push_back(n);
  }
  std::sort(frames.begin(), frames.end());
  frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
  return frames;
}

void add_sequence_options(CLI::App& app, SequenceArgs& args) {
  app.add_option("--frames", args.frames,
                 "With a sequence (a frame pattern, or a .pvd or .series collection): only frames FIRST:LAST "
                 "(inclusive, e.g. 10:250; or one number N); a frame in the range without its file is reported and "
                 "skipped (default: every file the pattern finds, or the collection lists)");
  app.add_flag("--force", args.force,
               "With a sequence (a frame pattern, or a .pvd or .series collection): mesh every frame again, even "
               "those whose outputs are newer than their input and were made with the same options (default: leave "
               "those alone)");
  app.add_option("--jobs", args.jobs,
                 "With a sequence (a frame pattern, or a .pvd or .series collection): mesh N frames at once (the "
                 "--threads are shared among them; each output is the same whatever N)")
      ->check(in_range(1, 1024))
      ->capture_default_str();
  app.add_flag("--dry-run", args.dry_run,
               "With a sequence (a frame pattern, or a .pvd or .series collection): list each frame, its input and "
               "outputs and whether it would be meshed or left alone (up to date), without reading any");
}

void check_single_file(const CLI::App& app, const std::vector<OutputSpec>& outputs) {
  for (const char* option : {"--frames", "--force", "--jobs", "--dry-run"})
    if (app.count(option) > 0)
      throw UsageError(std::string(option) + " is for a sequence: the input must be a frame pattern ({} or {:04d}, "
                       "e.g. sim/fluid_{:04d}.vtk) or a collection (.pvd, .series)");
  for (const OutputSpec& o : outputs)
    if (has_frame_field(o.path))
      throw UsageError(o.option + " '" + o.path +
                       "' holds a frame field but the input is not a sequence (a frame pattern, e.g. "
                       "sim/fluid_{:04d}.vtk, or a .pvd or .series collection)");
}

std::string sidecar_path(const std::string& output) {
  const std::string folder = folder_of(output);
  return (output.find('/') == std::string::npos ? std::string() : folder + "/") + "." + name_of(output) + ".particlemesh";
}

std::string options_text(const CLI::App& app, const std::vector<std::string>& ignored) {
  std::string text;
  for (const CLI::Option* o : app.get_options()) {
    if (o->count() == 0) continue;
    bool skip = false;
    for (const std::string& name : ignored) skip = skip || o->check_name(name);
    if (skip) continue;
    text += o->get_name() + "=";
    const auto& results = o->results();
    for (size_t i = 0; i < results.size(); ++i) text += (i ? "," : "") + results[i];
    text += "\n";
  }
  return text;
}

std::vector<OutputSpec> with_frame_outputs(std::vector<OutputSpec> specs, const FrameContext* frame) {
  if (frame) specs.insert(specs.end(), frame->extra_outputs.begin(), frame->extra_outputs.end());
  return specs;
}

void settle_attributes(PointCloud& cloud, const std::string& spec, FrameContext* frame) {
  select_attributes(cloud, spec);
  if (frame) frame->check_attributes(cloud.attributes);
}

void commit_outputs(RunOutputs& outputs, const FrameContext* frame) {
  if (frame)
    for (size_t i = 0; i < frame->extra_outputs.size(); ++i)
      outputs.open(frame->extra_outputs[i].option).write(frame->extra_contents[i]);
  outputs.commit_all();
}

int run_sequence(const SequenceSpec& spec) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const std::string& cmd = spec.command;
  // The frames' files: a pattern's, or those a collection (.pvd, .series) lists, frame n its
  // n-th by time.
  const bool collection = is_sequence_collection(spec.input);
  FramePattern input;
  std::vector<CollectionFrame> listed;
  if (collection) listed = read_frame_collection(spec.input);
  else input = parse_frame_pattern(spec.input, "input");
  auto input_of = [&](int64_t f) { return collection ? listed[size_t(f)].path : frame_path(input, f); };
  std::vector<FramePattern> outputs;
  for (const OutputSpec& o : spec.outputs) {
    if (o.path.empty()) {
      outputs.push_back({});
      continue;
    }
    if (!has_frame_field(o.path))
      throw UsageError(o.option + " '" + o.path + "' has no frame field, while the input '" + spec.input +
                       "' is a sequence: every frame would overwrite it (e.g. out/fluid_{:04d}.ply)");
    outputs.push_back(parse_frame_pattern(o.path, o.option));
    if (o.path == spec.input) throw UsageError(o.option + " '" + o.path + "' is the input pattern: it would overwrite the input");
    if (collection)
      for (const CollectionFrame& c : listed) {
        std::error_code ec;
        if (std::filesystem::equivalent(c.path, frame_path(outputs.back(), int64_t(&c - listed.data())), ec))
          throw UsageError(o.option + " '" + o.path + "' names the collection's frame '" + c.path +
                           "': it would overwrite the input");
      }
  }
  std::optional<std::pair<int64_t, int64_t>> range;
  if (!spec.sequence.frames.empty()) range = parse_frames(spec.sequence.frames);

  // The frames: the files found (in --frames' range); the gaps among them, or in the range,
  // are missing frames.
  std::vector<int64_t> found;
  if (collection) {
    for (size_t i = 0; i < listed.size(); ++i)
      if (regular_file(listed[i].path)) found.push_back(int64_t(i));
  } else {
    found = find_frames(input);
  }
  if (range) std::erase_if(found, [&](int64_t f) { return f < range->first || f > range->second; });
  std::vector<int64_t> missing_listed;
  size_t missing = 0;
  {
    // A collection's frames are 0..N-1 whatever --frames says: the files it lists that do not
    // exist are missing, also after the last one found.
    std::optional<std::pair<int64_t, int64_t>> bounds = range;
    if (collection) bounds = {range ? range->first : 0, range ? range->second : int64_t(listed.size()) - 1};
    int64_t expect = bounds ? bounds->first : found.empty() ? 0 : found.front();
    auto gap = [&](int64_t from, int64_t to) {  // [from, to)
      if (to <= from) return;
      missing += size_t(to - from);
      for (int64_t f = from; f < to && missing_listed.size() < 10; ++f) missing_listed.push_back(f);
    };
    for (int64_t f : found) {
      gap(expect, f);
      expect = f + 1;
    }
    if (bounds) gap(expect, bounds->second + 1);
  }
  if (found.empty()) {
    std::fprintf(stderr, "particlemesh %s: error: no frame: %s '%s'%s\n", cmd.c_str(),
                 collection ? "none of the files exists that is listed in" : "no file matches", spec.input.c_str(),
                 range ? (" in frames " + spec.sequence.frames).c_str() : "");
    return 1;
  }
  auto paths_of = [&](int64_t frame) {
    std::vector<OutputSpec> out = spec.outputs;
    for (size_t i = 0; i < out.size(); ++i)
      if (!out[i].path.empty()) out[i].path = frame_path(outputs[i], frame);
    return out;
  };
  // Every output of the first frame is checked as a run checks it (extension, folder,
  // collisions), before any frame is read: a bad -o is a usage error, not N failed frames.
  {
    const std::vector<OutputSpec> first = paths_of(found.front());
    RunOutputs check(first, {input_of(found.front())});
  }
  const std::string label_text = "particlemesh " PARTICLEMESH_VERSION_STRING "\ncommand=" + cmd + "\n";
  auto sidecar_text = [&](const std::string& in) { return label_text + "input=" + in + "\n" + spec.options_text; };

  // Which frames are up to date.
  struct Frame {
    int64_t number;
    std::string input;
    std::vector<OutputSpec> outputs;
    std::string sidecar;
  };
  std::vector<Frame> todo;
  std::vector<int64_t> up_to_date;
  for (int64_t f : found) {
    Frame fr{f, input_of(f), paths_of(f), {}};
    fr.sidecar = sidecar_path(fr.outputs.front().path);
    bool current = !spec.sequence.force;
    int64_t in_ns = 0;
    if (current) current = modified_ns(fr.input, in_ns);
    for (const OutputSpec& o : fr.outputs) {
      int64_t out_ns = 0;
      if (current && !o.path.empty()) current = modified_ns(o.path, out_ns) && out_ns > in_ns;
    }
    if (current) {  // the sidecar: the same options text, then the frame's attributes
      const std::string text = file_text(fr.sidecar), expected = sidecar_text(fr.input);
      current = text.compare(0, expected.size(), expected) == 0 &&
                text.compare(expected.size(), 11, "attributes=") == 0 &&
                text.find('\n', expected.size()) == text.size() - 1;
    }
    if (current)
      up_to_date.push_back(f);
    else
      todo.push_back(std::move(fr));
  }

  const bool quiet = spec.quiet;
  auto missing_line = [&]() {
    if (!missing) return;
    std::fprintf(stderr, "particlemesh %s: %zu missing frame%s skipped (no file): %s\n", cmd.c_str(), missing,
                 missing == 1 ? "" : "s", frame_list(missing_listed, missing).c_str());
    if (collection)  // the files the collection names
      for (int64_t f : missing_listed)
        if (f >= 0 && size_t(f) < listed.size())
          std::fprintf(stderr, "  frame %lld: '%s' is not a file\n", (long long)f, listed[size_t(f)].path.c_str());
  };
  if (spec.sequence.dry_run) {
    for (int64_t f : found) {
      const bool current = std::find(up_to_date.begin(), up_to_date.end(), f) != up_to_date.end();
      std::string outs;
      for (const OutputSpec& o : paths_of(f))
        if (!o.path.empty()) outs += (outs.empty() ? "" : ", ") + o.path;
      std::printf("frame %lld: %s -> %s (%s)\n", (long long)f, input_of(f).c_str(), outs.c_str(),
                  current ? "up to date: left alone" : "to mesh");
    }
    missing_line();
    return 0;
  }
  missing_line();

  // Run the frames, --jobs at once; --threads (0: all cores) shared among them.
  const int jobs = std::max(1, std::min<int>(spec.sequence.jobs, int(todo.size())));
  const int cores = spec.threads > 0 ? spec.threads : int(std::max(1u, std::thread::hardware_concurrency()));
  const int threads = std::max(1, cores / jobs);
  std::mutex mutex;  // guards what follows, and stderr lines
  std::atomic<size_t> next{0};
  size_t done = 0, finished = 0;
  struct Failure {
    int64_t frame;
    std::string message;
  };
  std::vector<Failure> failures;
  bool cancelled = false;
  // Every frame must carry the attributes of the sequence's first frame: read from its
  // sidecar when it is up to date, else that frame is meshed first, alone.
  std::optional<std::string> layout;
  int64_t layout_frame = 0;
  if (!up_to_date.empty() && (todo.empty() || up_to_date.front() < todo.front().number)) {
    const std::string text = file_text(sidecar_path(paths_of(up_to_date.front()).front().path));
    const size_t at = text.rfind("attributes=");
    layout = text.substr(at + 11, text.size() - at - 12);
    layout_frame = up_to_date.front();
  }
  const bool tty = !quiet && isatty(STDERR_FILENO) != 0;
  bool line_shown = false;
  auto draw = [&]() {  // with the mutex held
    if (!tty) return;
    const double s = std::chrono::duration<double>(Clock::now() - t0).count();
    std::fprintf(stderr, "\rframes %zu/%zu meshed, %zu failed, %s", done, todo.size(), failures.size(),
                 seconds_text(s).c_str());
    std::fflush(stderr);
    line_shown = true;
  };
  auto clear_line = [&]() {
    if (line_shown) std::fprintf(stderr, "\r%60s\r", "");
    line_shown = false;
  };

  hold_phase(true);
  auto worker = [&](bool one) {
    for (bool first = true; first || !one; first = false) {
      if (interrupted()) return;
      const size_t i = next.fetch_add(1);
      if (i >= todo.size()) return;
      const Frame& fr = todo[i];
      const std::string label = "frame " + std::to_string(fr.number);
      FrameContext ctx;
      ctx.label = label;
      ctx.extra_outputs.push_back({"the options sidecar", fr.sidecar, OutputKind::Text});
      ctx.extra_contents.push_back(sidecar_text(fr.input));
      ctx.check_attributes = [&, n = fr.number, c = &ctx](const std::vector<VertexAttribute>& attributes) {
        std::string mine;
        for (const VertexAttribute& a : attributes)
          mine += (mine.empty() ? "" : ", ") + a.name + "(" + std::to_string(a.components) + ")";
        if (mine.empty()) mine = "none";
        c->extra_contents.front() += "attributes=" + mine + "\n";
        std::lock_guard lock(mutex);
        if (!layout) {
          layout = mine;
          layout_frame = n;
        } else if (*layout != mine) {
          throw Error(Status::InvalidInput, "its particles carry the attributes " + mine + ", frame " +
                                                std::to_string(layout_frame) + "'s carry " + *layout +
                                                ": every frame of a sequence must carry the same (or pick them "
                                                "with --attributes)");
        }
      };
      ctx.warn = [&, label](const std::string& w) {
        std::lock_guard lock(mutex);
        clear_line();
        std::fprintf(stderr, "particlemesh %s: %s: warning: %s\n", cmd.c_str(), label.c_str(), w.c_str());
        draw();
      };
      const auto f0 = Clock::now();
      std::string error;
      bool cancel = false;
      try {
        spec.run_frame(fr.input, fr.outputs, threads, ctx);
      } catch (const Error& e) {
        error = e.what();
        cancel = e.status() == Status::Cancelled;
      } catch (const std::bad_alloc&) {
        error = "out of memory";
      } catch (const std::exception& e) {
        error = e.what();
      }
      const double secs = std::chrono::duration<double>(Clock::now() - f0).count();
      std::lock_guard lock(mutex);
      ++finished;
      clear_line();
      if (cancel || interrupted()) {
        cancelled = true;
      } else if (!error.empty()) {
        failures.push_back({fr.number, error});
        std::fprintf(stderr, "particlemesh %s: %s ('%s'): error: %s\n", cmd.c_str(), label.c_str(), fr.input.c_str(),
                     error.c_str());
      } else {
        ++done;
        if (!quiet && !tty)  // logs (render farms, CI): one line per frame
          std::fprintf(stderr, "%s: %s -> %s (%.2f s) [%zu/%zu]\n", label.c_str(), fr.input.c_str(),
                       fr.outputs.front().path.c_str(), secs, finished, todo.size());
      }
      draw();
    }
  };
  if (!layout) worker(true);  // the first frame, alone: its attributes are the reference
  std::vector<std::thread> pool;
  for (int j = 1; j < jobs; ++j) pool.emplace_back(worker, false);
  worker(false);
  for (std::thread& t : pool) t.join();
  hold_phase(false);
  clear_line();
  std::sort(failures.begin(), failures.end(), [](const Failure& a, const Failure& b) { return a.frame < b.frame; });

  const double secs = std::chrono::duration<double>(Clock::now() - t0).count();
  if (cancelled || interrupted()) {
    std::fprintf(stderr, "particlemesh %s: cancelled (interrupted) after %zu of %zu frames\n", cmd.c_str(), done,
                 todo.size());
    return 130;
  }
  if (!quiet) {
    std::printf("particlemesh %s: %s -> %s\n", cmd.c_str(), spec.input.c_str(), spec.outputs.front().path.c_str());
    std::printf("  frames        %zu found (%lld..%lld)%s\n", found.size(), (long long)found.front(),
                (long long)found.back(), range ? (", --frames " + spec.sequence.frames).c_str() : "");
    std::printf("  meshed        %zu in %s (%.2f frames/s, %d at once, %d thread%s each)\n", done,
                seconds_text(secs).c_str(), secs > 0 ? double(done) / secs : 0.0, jobs, threads,
                threads == 1 ? "" : "s");
    std::printf("  up to date    %zu left alone%s\n", up_to_date.size(),
                up_to_date.empty() ? "" : " (newer than their input, same options; --force redoes them)");
    if (missing) std::printf("  missing       %zu: %s\n", missing, frame_list(missing_listed, missing).c_str());
    std::printf("  failed        %zu\n", failures.size());
    for (const Failure& f : failures) std::printf("    frame %lld: %s\n", (long long)f.frame, f.message.c_str());
  }
  return failures.empty() ? 0 : 1;
}

}  // namespace particlemesh::cli
