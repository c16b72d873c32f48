// PCD in: the file is read into memory once; our header check runs on those bytes, then
// pcl::PCDReader reads the header from them and decodes binary and binary_compressed bodies
// from them (readBodyBinary); an ASCII body is parsed once, by the check itself, straight
// into the PCLPointCloud2 PCL's header reading laid out. PLY meshes out through PCL's writer,
// into an OutputFile (a temporary renamed into place, checked complete before).
#include <particlemesh_pcl/io.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <string_view>

#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

#include <particlemesh/core/error.h>
#include <particlemesh/io/mesh_io.h>
#include <particlemesh/io/output_file.h>

namespace particlemesh_pcl
{
  namespace
  {
    using particlemesh::Error;
    using particlemesh::Status;

    std::vector<std::string>
    split (std::string_view line)
    {
      std::vector<std::string> out;
      std::size_t i = 0;
      while (i < line.size ())
      {
        while (i < line.size () && std::isspace (static_cast<unsigned char> (line[i])))
          ++i;
        std::size_t j = i;
        while (j < line.size () && !std::isspace (static_cast<unsigned char> (line[j])))
          ++j;
        if (j > i)
          out.emplace_back (line.substr (i, j - i));
        i = j;
      }
      return out;
    }

    bool
    parseUnsigned (const std::string &s, std::size_t &v)
    {
      if (s.empty () || !std::isdigit (static_cast<unsigned char> (s[0])))
        return false;
      errno = 0;
      char *end = nullptr;
      const unsigned long long x = std::strtoull (s.c_str (), &end, 10);
      if (errno != 0 || *end != '\0')
        return false;
      v = static_cast<std::size_t> (x);
      return true;
    }

    bool
    parseNumber (const char *begin, const char *end)
    {
      // strtod accepts "nan", "inf" and what PCL's ascii writer prints
      std::string token (begin, end);
      char *stop = nullptr;
      std::strtod (token.c_str (), &stop);
      return stop == token.c_str () + token.size () && !token.empty ();
    }

    std::string
    lower (std::string s)
    {
      for (char &c : s)
        c = static_cast<char> (std::tolower (static_cast<unsigned char> (c)));
      return s;
    }

    [[noreturn]] void
    fail (const std::string &path, const std::string &problem)
    {
      throw Error (Status::FormatError, path + ": " + problem);
    }

    std::string
    joined (const std::vector<std::string> &v)
    {
      std::string s;
      for (const auto &x : v)
        s += (s.empty () ? "" : " ") + x;
      return s;
    }

    // The whole file, read once (PCD files are read whole by PCL too).
    std::string
    readFile (const std::string &path, std::size_t size)
    {
      std::ifstream in (path, std::ios::binary);
      if (!in)
        throw Error (Status::IoError, path + ": cannot open for reading");
      std::string out (size, '\0');
      in.read (out.data (), static_cast<std::streamsize> (size));
      if (in.bad ())
        throw Error (Status::IoError, path + ": read error");
      out.resize (static_cast<std::size_t> (in.gcount ()));
      return out;
    }

    std::size_t
    fileSize (const std::string &path)
    {
      std::error_code ec;
      if (!std::filesystem::exists (path, ec))
        throw Error (Status::IoError, path + ": no such file");
      if (std::filesystem::is_directory (path, ec))
        throw Error (Status::IoError, path + ": is a directory");
      const auto size = std::filesystem::file_size (path, ec);
      if (ec)
        throw Error (Status::IoError, path + ": cannot read (" + ec.message () + ")");
      return static_cast<std::size_t> (size);
    }

    constexpr std::size_t kMaxHeader = 1 << 20;

    // PDAL writes its dimension names (X Y Z Intensity); PCL's point types, and so the
    // conversion to particles, name the fields x y z intensity. A field whose name is one of
    // those in other letter case is taken as it where the file has none of that exact name.
    void
    lowerCaseFieldNames (const std::vector<std::string *> &names)
    {
      for (const std::string wanted : {"x", "y", "z", "intensity"})
      {
        if (std::any_of (names.begin (), names.end (), [&] (const std::string *f) { return *f == wanted; }))
          continue;
        const auto it = std::find_if (names.begin (), names.end (), [&] (const std::string *f) { return lower (*f) == wanted; });
        if (it != names.end ())
          **it = wanted;
      }
    }

  // The header (and the sizes of a binary body) of the PCD file whose bytes are `file`;
  // `line_no` gets the number of the DATA line.
  PCDHeader
  checkHeader (const std::string &path, const std::string &file, std::size_t &line_no)
  {
    const std::size_t file_size = file.size ();
    if (file_size == 0)
      fail (path, "empty file, not a PCD file");
    const std::string bytes = file.substr (0, std::min (file_size, kMaxHeader));

    PCDHeader h;
    bool seen_fields = false, seen_size = false, seen_type = false, seen_count = false;
    bool seen_width = false, seen_points = false, seen_data = false;
    std::size_t pos = 0;
    line_no = 0;
    while (pos < bytes.size () && !seen_data)
    {
      std::size_t eol = bytes.find ('\n', pos);
      const bool last = eol == std::string::npos;
      if (last)
        eol = bytes.size ();
      const std::string_view line (bytes.data () + pos, eol - pos);
      pos = last ? eol : eol + 1;
      ++line_no;
      // pcl::PCDReader splits a header line at spaces, tabs and CRs only: "DATA\fbinary" is one
      // word to it, and it threw out of its reader (an abort, found by fuzzing) where our split
      // saw two. Other control bytes have no place in a header, so refuse them all.
      for (const char c : line)
        if ((static_cast<unsigned char> (c) < 0x20 && c != '\t' && c != '\r') || c == '\x7f')
        {
          char hex[8];
          std::snprintf (hex, sizeof hex, "0x%02x", static_cast<unsigned> (static_cast<unsigned char> (c)));
          fail (path, "header line " + std::to_string (line_no) + " holds the control byte " + hex +
                      "; a PCD header holds only text, spaces and tabs");
        }
      const std::vector<std::string> tok = split (line);
      // A line of only whitespace (" ", "\t", a CRLF blank line) makes pcl::PCDReader crash
      // before the first keyword and stop reading after it (found by fuzzing). Empty lines are fine.
      if (tok.empty () && !line.empty ())
        fail (path, "header line " + std::to_string (line_no) + " holds only whitespace, which PCL's reader cannot read");
      if (tok.empty () || tok[0][0] == '#')
        continue;
      const std::string &key = tok[0];
      const std::vector<std::string> args (tok.begin () + 1, tok.end ());
      const std::string where = "header line " + std::to_string (line_no) + " (" + key + ")";

      auto unsignedArgs = [&] (std::vector<int> &out) {
        out.clear ();
        for (const auto &a : args)
        {
          std::size_t v;
          if (!parseUnsigned (a, v) || v > 1u << 20)
            fail (path, "bad header: " + where + ": '" + a + "' is not a count");
          out.push_back (static_cast<int> (v));
        }
      };
      auto one = [&] () -> std::size_t {
        std::size_t v;
        if (args.size () != 1 || !parseUnsigned (args[0], v))
          fail (path, "bad header: " + where + " needs one non-negative integer");
        return v;
      };

      if (key == "VERSION")
        h.version = args.empty () ? "" : args[0];
      else if (key == "FIELDS" || key == "COLUMNS")
      {
        h.fields = args;
        seen_fields = true;
      }
      else if (key == "SIZE")
      {
        unsignedArgs (h.sizes);
        seen_size = true;
      }
      else if (key == "TYPE")
      {
        h.types.clear ();
        for (const auto &a : args)
        {
          if (a.size () != 1 || (a[0] != 'F' && a[0] != 'U' && a[0] != 'I'))
            fail (path, "bad header: " + where + ": type '" + a + "' is not F, U or I");
          h.types.push_back (a[0]);
        }
        seen_type = true;
      }
      else if (key == "COUNT")
      {
        unsignedArgs (h.counts);
        seen_count = true;
      }
      else if (key == "WIDTH")
      {
        const std::size_t w = one ();
        if (w > 0xffffffffu)
          fail (path, "bad header: WIDTH " + args[0] + " is too large");
        h.width = static_cast<std::uint32_t> (w);
        seen_width = true;
      }
      else if (key == "HEIGHT")
      {
        const std::size_t v = one ();
        if (v > 0xffffffffu)
          fail (path, "bad header: HEIGHT " + args[0] + " is too large");
        h.height = static_cast<std::uint32_t> (v);
      }
      else if (key == "VIEWPOINT")
      {
        if (args.size () != 7)
          fail (path, "bad header: " + where + " needs 7 numbers (tx ty tz qw qx qy qz), has " +
                      std::to_string (args.size ()));
        for (int k = 0; k < 7; ++k)
        {
          if (!parseNumber (args[k].data (), args[k].data () + args[k].size ()))
            fail (path, "bad header: " + where + ": '" + args[k] + "' is not a number");
          h.viewpoint[k] = std::strtof (args[k].c_str (), nullptr);
        }
      }
      else if (key == "POINTS")
      {
        h.points = one ();
        seen_points = true;
      }
      else if (key == "DATA")
      {
        if (args.size () != 1)
          fail (path, "bad header: " + where + " needs one of ascii, binary, binary_compressed");
        h.data = lower (args[0]);
        if (h.data != "ascii" && h.data != "binary" && h.data != "binary_compressed")
          fail (path, "bad header: DATA '" + args[0] + "' is not ascii, binary or binary_compressed");
        h.data_offset = pos;
        seen_data = true;
      }
      else
      {
        const std::string shown = key.size () > 20 ? key.substr (0, 20) + "..." : key;
        fail (path, "not a PCD file: header line " + std::to_string (line_no) + " starts with '" + shown +
                    "', not a PCD keyword");
      }
    }

    // What a header must have, and what must agree.
    if (!seen_data)
      fail (path, file_size > bytes.size () ? "not a PCD file: no DATA line in the first MiB"
                                            : "truncated header: no DATA line");
    // pcl::PCDReader::readHeader goes on reading lines after DATA until one does not start with
    // a header keyword (or a comment): binary data beginning with the bytes "COLUMNS" became a
    // second FIELDS line, and PCL then read the points with garbage fields and crashed (found
    // by fuzzing). Refuse what it would misread.
    for (std::size_t p = h.data_offset; p < bytes.size ();)
    {
      std::size_t eol = bytes.find ('\n', p);
      if (eol == std::string::npos)
        eol = bytes.size ();
      const std::vector<std::string> tok = split (std::string_view (bytes.data () + p, eol - p));
      p = eol + 1;
      if (tok.empty () || tok[0][0] == '#')
        continue;  // PCL skips these and reads the next line as header too
      for (const char *key : {"VERSION", "FIELDS", "COLUMNS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT",
                              "VIEWPOINT", "POINTS", "DATA"})
        if (tok[0].rfind (key, 0) == 0)
          fail (path, "the data after the DATA line begins like a header line ('" + std::string (key) +
                      "...'): PCL's reader would read it as one");
      break;
    }
    if (!seen_fields || h.fields.empty ())
      fail (path, "bad header: no FIELDS");
    if (!seen_size)
      fail (path, "bad header: no SIZE line");
    if (!seen_type)
      fail (path, "bad header: no TYPE line");
    if (!seen_width)
      fail (path, "bad header: no WIDTH line");
    if (!seen_count)
      h.counts.assign (h.fields.size (), 1);
    const std::size_t nf = h.fields.size ();
    if (h.sizes.size () != nf)
      fail (path, "header count mismatch: SIZE has " + std::to_string (h.sizes.size ()) + " entries, FIELDS has " +
                  std::to_string (nf));
    if (h.types.size () != nf)
      fail (path, "header count mismatch: TYPE has " + std::to_string (h.types.size ()) + " entries, FIELDS has " +
                  std::to_string (nf));
    if (h.counts.size () != nf)
      fail (path, "header count mismatch: COUNT has " + std::to_string (h.counts.size ()) + " entries, FIELDS has " +
                  std::to_string (nf));
    h.point_size = 0;
    for (std::size_t f = 0; f < nf; ++f)
    {
      const int s = h.sizes[f];
      const bool ok = h.types[f] == 'F' ? (s == 4 || s == 8) : (s == 1 || s == 2 || s == 4 || s == 8);
      if (!ok)
        fail (path, "bad header: field '" + h.fields[f] + "' has TYPE " + h.types[f] + " with SIZE " + std::to_string (s));
      h.point_size += std::size_t (s) * std::size_t (h.counts[f]);
    }
    {
      std::vector<std::string *> names;
      for (std::string &f : h.fields)
        names.push_back (&f);
      lowerCaseFieldNames (names);
    }
    for (const char *axis : {"x", "y", "z"})
    {
      const auto it = std::find (h.fields.begin (), h.fields.end (), axis);
      if (it == h.fields.end ())
        fail (path, std::string ("missing field '") + axis + "' (FIELDS: " + joined (h.fields) + ")");
      if (h.counts[std::size_t (it - h.fields.begin ())] != 1)
        fail (path, std::string ("field '") + axis + "' must have COUNT 1");
    }
    if (!seen_points)
      h.points = std::size_t (h.width) * h.height;  // old files may omit POINTS
    if (std::size_t (h.width) * h.height != h.points)
      fail (path, "count mismatch: WIDTH " + std::to_string (h.width) + " x HEIGHT " + std::to_string (h.height) +
                  " = " + std::to_string (std::size_t (h.width) * h.height) + " points, but POINTS says " +
                  std::to_string (h.points));
    if (h.points == 0)
      fail (path, "no points (POINTS 0)");

    // The data section. points x point_size can exceed 64 bits in a hostile header.
    const std::size_t available = file_size - h.data_offset;
    if (h.points > std::numeric_limits<std::size_t>::max () / h.point_size)
      fail (path, "bad header: " + std::to_string (h.points) + " points x " + std::to_string (h.point_size) +
                  " bytes per point is more than any file holds");
    if (h.data == "binary")
    {
      const std::size_t need = h.points * h.point_size;
      if (available < need)
        fail (path, "truncated data: " + std::to_string (available) + " bytes after the header, " +
                    std::to_string (h.points) + " points x " + std::to_string (h.point_size) + " bytes need " +
                    std::to_string (need));
    }
    else if (h.data == "binary_compressed")
    {
      if (available < 8)
        fail (path, "truncated data: no compressed block header after DATA");
      std::uint32_t sizes[2];
      std::memcpy (sizes, file.data () + h.data_offset, 8);
      if (std::size_t (sizes[0]) > available - 8)
        fail (path, "truncated data: compressed block of " + std::to_string (sizes[0]) + " bytes, only " +
                    std::to_string (available - 8) + " left");
      if (std::size_t (sizes[1]) != h.points * h.point_size)
        fail (path, "count mismatch: compressed block unpacks to " + std::to_string (sizes[1]) + " bytes, " +
                    std::to_string (h.points) + " points x " + std::to_string (h.point_size) + " bytes = " +
                    std::to_string (h.points * h.point_size));
    }
    return h;
  }

  // The values of a PCLPointCloud2 field, stored from text.
  void
  storeValue (const std::string &path, std::size_t file_line, const pcl::PCLPointField &f, double v,
              std::uint8_t *at, bool &dense)
  {
    auto integer = [&] (auto t) {
      using T = decltype (t);
      if (!std::isfinite (v))
        fail (path, "bad data: line " + std::to_string (file_line) + ": a non-finite value in integer field '" +
                    f.name + "'");
      // Saturated to the type's range (double(INT64_MAX) rounds up to 2^63, itself out of
      // range: compare, do not convert, at the ends).
      const double lo = double (std::numeric_limits<T>::lowest ()), hi = double (std::numeric_limits<T>::max ());
      const double w = std::trunc (v);
      const T x = w >= hi ? std::numeric_limits<T>::max () : w <= lo ? std::numeric_limits<T>::lowest () : static_cast<T> (w);
      std::memcpy (at, &x, sizeof x);
    };
    switch (f.datatype)
    {
      case pcl::PCLPointField::INT8: integer (std::int8_t {}); break;
      case pcl::PCLPointField::UINT8: integer (std::uint8_t {}); break;
      case pcl::PCLPointField::INT16: integer (std::int16_t {}); break;
      case pcl::PCLPointField::UINT16: integer (std::uint16_t {}); break;
      case pcl::PCLPointField::INT32: integer (std::int32_t {}); break;
      case pcl::PCLPointField::UINT32: integer (std::uint32_t {}); break;
      case pcl::PCLPointField::INT64: integer (std::int64_t {}); break;
      case pcl::PCLPointField::UINT64: integer (std::uint64_t {}); break;
      case pcl::PCLPointField::FLOAT32:
      {
        const float x = static_cast<float> (v);
        dense = dense && std::isfinite (x);
        std::memcpy (at, &x, sizeof x);
        break;
      }
      case pcl::PCLPointField::FLOAT64:
        dense = dense && std::isfinite (v);
        std::memcpy (at, &v, sizeof v);
        break;
      default:
        fail (path, "field '" + f.name + "' has a type PCL's header reading did not expect");
    }
  }

  // An ASCII body: one line per point, every value a number, as many as FIELDS x COUNT say.
  // With `cloud` (laid out by PCL's readHeader), the values are stored into it: the body is
  // parsed once, here.
  void
  readAsciiBody (const std::string &path, const std::string &file, const PCDHeader &h, std::size_t line_no,
                 pcl::PCLPointCloud2 *cloud)
  {
    std::size_t values_per_point = 0;
    for (int c : h.counts)
      values_per_point += std::size_t (c);
    // Where each value of a line goes: the field and the byte offset in the point.
    std::vector<std::pair<const pcl::PCLPointField *, std::size_t>> slots;
    if (cloud)
    {
      if (cloud->fields.size () != h.fields.size () ||
          std::size_t (cloud->width) * cloud->height != h.points ||
          cloud->data.size () != h.points * std::size_t (cloud->point_step))
        fail (path, "PCL's reading of the header disagrees with ours");
      for (const auto &f : cloud->fields)
        for (std::uint32_t c = 0; c < f.count; ++c)
          slots.emplace_back (&f, f.offset + c * pcl::getFieldSize (f.datatype));
      if (slots.size () != values_per_point)
        fail (path, "PCL's reading of the header disagrees with ours (values per point)");
      cloud->is_dense = true;
    }
    bool dense = true;
    const std::string_view body (file.data () + h.data_offset, file.size () - h.data_offset);
    {
      std::size_t rows = 0;
      std::size_t p = 0;
      std::size_t file_line = line_no;
      while (p < body.size () && rows < h.points)
      {
        std::size_t eol = body.find ('\n', p);
        if (eol == std::string::npos)
          eol = body.size ();
        ++file_line;
        const char *b = body.data () + p;
        const char *e = body.data () + eol;
        p = eol + 1;
        std::size_t values = 0;
        const char *q = b;
        while (q < e)
        {
          while (q < e && std::isspace (static_cast<unsigned char> (*q)))
            ++q;
          const char *t = q;
          while (q < e && !std::isspace (static_cast<unsigned char> (*q)))
            ++q;
          if (q > t)
          {
            if (!parseNumber (t, q))
              fail (path, "bad data: line " + std::to_string (file_line) + ": '" +
                          std::string (t, std::min<std::size_t> (std::size_t (q - t), 20)) + "' is not a number");
            if (cloud && values < slots.size ())
            {
              const std::string token (t, q);
              const double v = std::strtod (token.c_str (), nullptr);
              std::uint8_t *at = cloud->data.data () + rows * std::size_t (cloud->point_step) + slots[values].second;
              storeValue (path, file_line, *slots[values].first, v, at, dense);
            }
            ++values;
          }
        }
        if (values == 0)
          continue;  // blank line
        if (values != values_per_point)
          fail (path, "bad data: line " + std::to_string (file_line) + " has " + std::to_string (values) +
                      " values, FIELDS/COUNT need " + std::to_string (values_per_point));
        ++rows;
      }
      if (rows < h.points)
        fail (path, "truncated data: " + std::to_string (rows) + " data lines, POINTS says " + std::to_string (h.points));
    }
    if (cloud)
      cloud->is_dense = dense;
  }
  }  // namespace

  PCDHeader
  checkPCDFile (const std::string &path)
  {
    const std::string file = readFile (path, fileSize (path));
    std::size_t line_no = 0;
    PCDHeader h = checkHeader (path, file, line_no);
    if (h.data == "ascii")
      readAsciiBody (path, file, h, line_no, nullptr);
    return h;
  }

  PCDFile
  loadPCDFile (const std::string &path)
  {
    PCDFile file;
    const std::string bytes = readFile (path, fileSize (path));
    std::size_t line_no = 0;
    file.header = checkHeader (path, bytes, line_no);
    Eigen::Vector4f origin;
    Eigen::Quaternionf orientation;
    int version = 0, data_type = 0;
    unsigned int data_idx = 0;
    pcl::PCDReader reader;
    std::istringstream header (bytes);
    int rc = reader.readHeader (header, file.cloud, origin, orientation, version, data_type, data_idx);
    if (rc >= 0)
    {
      std::vector<std::string *> names;
      for (pcl::PCLPointField &f : file.cloud.fields)
        names.push_back (&f.name);
      lowerCaseFieldNames (names);
      if (data_type == 0)
        readAsciiBody (path, bytes, file.header, line_no, &file.cloud);
      else if (data_idx > bytes.size ())
        rc = -1;
      else
        rc = reader.readBodyBinary (reinterpret_cast<const unsigned char *> (bytes.data ()), file.cloud, version,
                                    data_type == 2, data_idx);
    }
    if (rc < 0)
      throw Error (Status::FormatError, path + ": PCL's PCD reader failed (code " + std::to_string (rc) + ")");
    if (std::size_t (file.cloud.width) * file.cloud.height != file.header.points)
      throw Error (Status::FormatError, path + ": PCL read " +
                                        std::to_string (std::size_t (file.cloud.width) * file.cloud.height) +
                                        " points, the header says " + std::to_string (file.header.points));
    for (int c = 0; c < 4; ++c)
      file.origin[c] = origin[c];
    file.orientation[0] = orientation.w ();
    file.orientation[1] = orientation.x ();
    file.orientation[2] = orientation.y ();
    file.orientation[3] = orientation.z ();
    return file;
  }

  particlemesh::PointCloud
  loadParticles (const std::string &path, LoadReport *report, pcl::Indices *index_map)
  {
    LoadReport r;
    pcl::Indices map;
    particlemesh::PointCloud particles;
    const std::string ext = lower (std::filesystem::path (path).extension ().string ());
    if (ext == ".pcd")
    {
      const PCDFile file = loadPCDFile (path);
      r.format = "pcd";
      r.encoding = file.header.data;
      for (int c = 0; c < 3; ++c)
        r.origin[c] = file.origin[c];
      try
      {
        r.conversion = toParticles (file.cloud, particles, map);
      }
      catch (const Error &e)
      {
        throw Error (e.status (), path + ": " + e.what ());
      }
      if (particles.positions.empty ())
        throw Error (Status::InvalidInput, path + ": no valid point (all " + std::to_string (r.conversion.input_points) +
                                           " have a NaN or infinite coordinate)");
    }
    else
    {
      particles = particlemesh::read_point_cloud (path);
      r.format = ext.empty () ? "" : ext.substr (1);
      r.conversion.input_points = r.conversion.valid_points = particles.size ();
      r.conversion.width = static_cast<std::uint32_t> (particles.size ());
      r.conversion.height = 1;
      r.conversion.has_normals = particles.has_normals ();
      map.resize (particles.size ());
      for (std::size_t i = 0; i < map.size (); ++i)
        map[i] = static_cast<pcl::index_t> (i);
    }
    if (report)
      *report = r;
    if (index_map)
      *index_map = std::move (map);
    return particles;
  }

  void
  savePLYFile (particlemesh::OutputFile &out, const pcl::PolygonMesh &mesh)
  {
    const std::string target = out.path_for_external_writer ();
    if (pcl::io::savePLYFileBinary (target, mesh) < 0)
      throw Error (Status::IoError, "cannot write '" + out.path () + "': PCL's PLY writer failed");
    if (out.streams ())
      return;  // a device or FIFO: written straight through, nothing to read back
    // PCL's writer does not check its stream: a write cut short (disk full, file size limit)
    // still returns 0. The file must read back complete before it is put in place.
    try
    {
      particlemesh::read_mesh (target);
    }
    catch (const Error &)
    {
      throw Error (Status::IoError, "cannot write '" + out.path () + "': the file came out incomplete (disk full?)");
    }
  }

  void
  savePLYFile (const std::string &path, const pcl::PolygonMesh &mesh)
  {
    particlemesh::OutputFile out (path);
    savePLYFile (out, mesh);
    out.commit ();
  }
}
