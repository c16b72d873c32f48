// Houdini 12+'s geometry in binary JSON (.bgeo, and gzip-compressed .bgeo.gz): what Houdini
// writes for particle caches by default; and its ASCII form (.geo): the same schema as text
// JSON (TextParser).
//
// Written by hand: no Debian package reads it (Houdini's own reader, UT_JSONParser, is in
// the proprietary HDK). The encoding is SideFX's binary JSON as documented in the HDK's
// UT_JSONDefines.h: one byte per token ({ } [ ] null false true, 8-64 bit integers, 16-64 bit
// reals, strings with an encoded length, token-defined strings referenced by id, and uniform
// arrays: one element type, an encoded count, then the raw values), multi-byte values in the
// byte order that the magic number after the leading 0x7f gives. The geometry schema is the
// one SideFX's own Python reader (hgeo.py, shipped with Houdini) interprets: the file is a
// list of key/value pairs; "pointcount" counts the points; "attributes" holds
// "pointattributes", a list of [definition, values] pairs, the definition naming the
// attribute ("name") and its "type", the values giving the tuple "size" and the numbers in
// one of three layouts (Schema::decode below).
//
// What comes back: P as the positions, N (3 values) as the normals, and every other numeric
// point attribute under its Houdini name, as floats ("v" becomes the channel "velocity":
// name_the_velocity). String attributes (named in not_read), vertex, primitive and detail
// attributes, groups and primitives are walked (a truncated or malformed file is refused) but
// not carried, nor anything after the geometry's value (the seek index of a file written
// with "hasindex").
// Bounded: nesting depth, string lengths, the structure's node count, and the values a file
// may expand to through constant pages (at most 64 per stored byte), so that a hostile file
// is refused before it takes memory out of proportion to its size.
#include "io/bgeo_json.h"
#include "io/scalar_types.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <string>
#include <unordered_map>
#include <vector>

#include "io/text_numbers.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

namespace {

// Multi-byte values are stored in the writer's byte order; a big-endian file is swapped.
static_assert(std::endian::native == std::endian::little, "the binary JSON reader assumes a little-endian host");

// Token bytes (UT_JID in the HDK).
enum : uint8_t {
  kNull = 0x00,
  kMapBegin = 0x7b,
  kMapEnd = 0x7d,
  kArrayBegin = 0x5b,
  kArrayEnd = 0x5d,
  kBool = 0x10,
  kInt8 = 0x11,
  kInt16 = 0x12,
  kInt32 = 0x13,
  kInt64 = 0x14,
  kReal16 = 0x18,
  kReal32 = 0x19,
  kReal64 = 0x1a,
  kUint8 = 0x21,
  kUint16 = 0x22,
  kString = 0x27,
  kFalse = 0x30,
  kTrue = 0x31,
  kTokenDef = 0x2b,
  kTokenRef = 0x26,
  kTokenUndef = 0x2d,
  kUniformArray = 0x40,
};

constexpr int kMaxDepth = 64;
constexpr uint64_t kMaxString = uint64_t(1) << 26;     // 64 MiB
constexpr uint64_t kMaxNodes = uint64_t(1) << 24;      // values outside uniform arrays
constexpr uint64_t kMaxPageSize = uint64_t(1) << 16;   // Houdini writes 1024
constexpr uint64_t kValuesPerByte = 64;                // what constant pages may expand to

/// Bytes of one element of a numeric uniform array (0: not numeric).
size_t element_bytes(uint8_t type) {
  switch (type) {
    case kInt8: case kUint8: return 1;
    case kInt16: case kUint16: case kReal16: return 2;
    case kInt32: case kReal32: return 4;
    case kInt64: case kReal64: return 8;
    default: return 0;
  }
}

/// The number of `type` (a numeric token, element_bytes > 0) stored at `b` in the file's byte
/// order (`swap`: big-endian): a single value's and a uniform array's element alike.
double number_at(uint8_t type, const unsigned char* b, bool swap) {
  const size_t each = element_bytes(type);
  unsigned char v[8];
  std::memcpy(v, b, each);
  if (swap) std::reverse(v, v + each);
  switch (type) {
    case kInt8: return double(int8_t(v[0]));
    case kUint8: return double(v[0]);
    case kInt16: { int16_t x; std::memcpy(&x, v, 2); return x; }
    case kUint16: { uint16_t x; std::memcpy(&x, v, 2); return x; }
    case kReal16: { uint16_t x; std::memcpy(&x, v, 2); return half_to_double(x); }
    case kInt32: { int32_t x; std::memcpy(&x, v, 4); return x; }
    case kReal32: { float x; std::memcpy(&x, v, 4); return x; }
    case kInt64: { int64_t x; std::memcpy(&x, v, 8); return double(x); }
    default: { double x; std::memcpy(&x, v, 8); return x; }
  }
}

/// The error every part of the reader raises: the file, then what was wrong.
[[noreturn]] void fail_in(const std::string& path, const std::string& problem) {
  throw Error(Status::FormatError, "'" + path + "': " + problem);
}

struct Node {
  enum class Kind : uint8_t { Null, Bool, Number, String, List, Map, Uniform };
  Kind kind = Kind::Null;
  uint8_t type = 0;               // Uniform: its elements' token
  double number = 0;              // Bool (0 or 1), Number
  uint64_t count = 0;             // Uniform: its elements
  std::string text;               // String; Uniform: the elements' bytes as stored
  std::vector<Node> items;        // List; Map: the values
  std::vector<std::string> keys;  // Map: the keys
};

class Parser {
 public:
  Parser(DecompressedStream& in, const std::string& path, bool big_endian) : in_(in), path_(path), swap_(big_endian) {}

  /// The file's one value. What may follow it (the seek index of a file whose "hasindex" is
  /// true) is not read.
  Node parse_document() { return value(next_token(), 0); }

  uint64_t bytes_read() const { return in_.offset(); }

  [[noreturn]] void fail(const std::string& problem) const { fail_in(path_, problem); }

 private:
  static std::string hex(uint8_t b) {
    const char* d = "0123456789abcdef";
    return std::string{d[b >> 4], d[b & 15]};
  }
  [[noreturn]] void truncated() const {
    fail("truncated: the binary JSON ends inside a value (after " + std::to_string(in_.offset()) + " bytes" +
         (in_.compressed() ? " of decompressed data" : "") + ")");
  }
  void read(void* out, size_t n) {
    if (!in_.read(out, n)) truncated();
  }
  uint8_t byte() {
    uint8_t b;
    read(&b, 1);
    return b;
  }
  template <class T>
  T scalar() {
    unsigned char b[sizeof(T)];
    read(b, sizeof(T));
    if (swap_) std::reverse(b, b + sizeof(T));
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
  }
  /// An encoded length or id: one byte below 0xf1, or 0xf2 / 0xf4 / 0xf8 and 2 / 4 / 8 bytes.
  uint64_t length() {
    const uint8_t lead = byte();
    if (lead < 0xf1) return lead;
    if (lead == 0xf2) return scalar<uint16_t>();
    if (lead == 0xf4) return scalar<uint32_t>();
    if (lead == 0xf8) {
      const int64_t v = scalar<int64_t>();
      if (v < 0) fail("a negative length (" + std::to_string(v) + ")");
      return uint64_t(v);
    }
    fail("an invalid length prefix 0x" + hex(lead));
  }
  std::string string() {
    const uint64_t n = length();
    if (n > kMaxString) fail("a string of " + std::to_string(n) + " bytes (at most 64 MiB are read)");
    std::string s(size_t(n), '\0');
    read(s.data(), s.size());
    return s;
  }
  void token_definition(uint8_t t) {
    const uint64_t id = length();
    if (t == kTokenUndef) {
      tokens_.erase(id);
      return;
    }
    count_node();
    tokens_[id] = string();  // a definition replaces an earlier one of the same id
  }
  const std::string& token(uint64_t id) const {
    const auto it = tokens_.find(id);
    if (it == tokens_.end()) fail("a reference to string token " + std::to_string(id) + ", which was never defined");
    return it->second;
  }
  /// The next token that is not a token (un)definition.
  uint8_t next_token() {
    for (;;) {
      const uint8_t t = byte();
      if (t != kTokenDef && t != kTokenUndef) return t;
      token_definition(t);
    }
  }
  void count_node() {
    if (++nodes_ > kMaxNodes)
      fail("more than " + std::to_string(kMaxNodes) + " values outside uniform arrays (not a plausible geometry file)");
  }

  Node value(uint8_t t, int depth) {
    if (depth > kMaxDepth) fail("values nested more than " + std::to_string(kMaxDepth) + " deep");
    count_node();
    Node n;
    switch (t) {
      case kNull: return n;
      case kFalse: case kTrue:
        n.kind = Node::Kind::Bool;
        n.number = t == kTrue;
        return n;
      case kBool:
        n.kind = Node::Kind::Bool;
        n.number = byte() != 0;
        return n;
      case kInt8: case kInt16: case kInt32: case kInt64: case kUint8: case kUint16: case kReal16: case kReal32:
      case kReal64: {
        unsigned char b[8];
        read(b, element_bytes(t));
        n.number = number_at(t, b, swap_);
        break;
      }
      case kString:
        n.kind = Node::Kind::String;
        n.text = string();
        return n;
      case kTokenRef:
        n.kind = Node::Kind::String;
        n.text = token(length());
        return n;
      case kUniformArray: return uniform();
      case kArrayBegin: {
        n.kind = Node::Kind::List;
        for (uint8_t c = next_token(); c != kArrayEnd; c = next_token()) n.items.push_back(value(c, depth + 1));
        return n;
      }
      case kMapBegin: {
        n.kind = Node::Kind::Map;
        for (uint8_t c = next_token(); c != kMapEnd; c = next_token()) {
          if (c != kString && c != kTokenRef) fail("a map key that is not a string (token 0x" + hex(c) + ")");
          n.keys.push_back(c == kString ? string() : token(length()));
          n.items.push_back(value(next_token(), depth + 1));
        }
        return n;
      }
      default: fail("an unknown binary JSON token 0x" + hex(t));
    }
    n.kind = Node::Kind::Number;
    return n;
  }

  Node uniform() {
    Node n;
    n.type = byte();
    n.count = length();
    if (n.type == kString || n.type == kTokenRef) {  // a list of strings
      n.kind = Node::Kind::List;
      for (uint64_t i = 0; i < n.count; ++i) {
        count_node();
        Node s;
        s.kind = Node::Kind::String;
        s.text = n.type == kString ? string() : token(length());
        n.items.push_back(std::move(s));
      }
      n.count = 0;
      return n;
    }
    n.kind = Node::Kind::Uniform;
    uint64_t bytes;
    if (n.type == kBool) {
      bytes = (n.count + 31) / 32 * 4;  // bits packed in 32-bit words
    } else {
      const size_t each = element_bytes(n.type);
      if (each == 0) fail("a uniform array of token 0x" + hex(n.type) + ", which uniform arrays do not hold");
      if (n.count > (uint64_t(1) << 40)) fail("a uniform array of " + std::to_string(n.count) + " values");
      bytes = n.count * each;
    }
    // Read in pieces: the count alone sizes nothing (a truncated or lying file ends first).
    constexpr uint64_t kPiece = uint64_t(1) << 20;
    for (uint64_t done = 0; done < bytes;) {
      const size_t step = size_t(std::min(kPiece, bytes - done));
      n.text.resize(size_t(done) + step);
      read(n.text.data() + done, step);
      done += step;
    }
    return n;
  }

  DecompressedStream& in_;
  const std::string& path_;
  bool swap_;
  std::unordered_map<uint64_t, std::string> tokens_;
  uint64_t nodes_ = 0;
};

/// Houdini's ASCII geometry (.geo): the same schema as text JSON. A list of plain numbers is
/// kept as one array of doubles (8 bytes a number, not a value each: a .geo's points are
/// such lists); any other list as values.
class TextParser {
 public:
  TextParser(DecompressedStream& in, const std::string& path, std::string_view read_already)
      : in_(in), path_(path), pending_(read_already) {}

  /// The file's one value; what follows it is not read.
  Node parse_document() { return value(0); }
  uint64_t bytes_read() const { return in_.offset(); }

 private:
  [[noreturn]] void fail(const std::string& problem) const {
    fail_in(path_, problem + " (ASCII geometry, near byte " + std::to_string(in_.offset()) + ")");
  }
  int peek() {
    if (next_ < 0) next_ = take();
    return next_;
  }
  int get() {
    const int c = peek();
    next_ = -1;
    return c;
  }
  int take() {
    if (at_ < pending_.size()) return static_cast<unsigned char>(pending_[at_++]);
    unsigned char c;
    return in_.read(&c, 1) ? c : -1;
  }
  int after_space() {
    while (peek() == ' ' || peek() == '\n' || peek() == '\r' || peek() == '\t') get();
    return peek();
  }
  void expect(char c) {
    if (after_space() != c) fail(std::string("'") + c + "' expected");
    get();
  }
  void count_node() {
    if (++nodes_ > kMaxNodes)
      fail("more than " + std::to_string(kMaxNodes) + " values outside lists of numbers (not a plausible geometry file)");
  }
  static bool starts_number(int c) { return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.'; }
  double number() {
    std::string t;
    while (starts_number(peek()) || peek() == 'e' || peek() == 'E') {
      t += char(get());
      if (t.size() > 64) fail("a number of more than 64 characters");
    }
    double v = 0;
    if (parse_number(t, v) != NumberText::Ok) fail("'" + shown(t) + "' is not a number");
    return v;
  }
  std::string string() {
    get();  // the opening quote
    std::string out;
    for (;;) {
      int c = get();
      if (c < 0) fail("the file ends inside a string");
      if (c == '"') return out;
      if (c == '\\') {
        c = get();
        switch (c) {
          case 'b': c = '\b'; break;
          case 'f': c = '\f'; break;
          case 'n': c = '\n'; break;
          case 'r': c = '\r'; break;
          case 't': c = '\t'; break;
          case 'u': {
            unsigned code = 0;
            for (int k = 0; k < 4; ++k) {
              const int h = get();
              const int d = h >= '0' && h <= '9' ? h - '0' : h >= 'a' && h <= 'f' ? h - 'a' + 10 : h >= 'A' && h <= 'F' ? h - 'A' + 10 : -1;
              if (d < 0) fail("a \\u escape without four hexadecimal digits");
              code = code * 16 + unsigned(d);
            }
            // UTF-8 (names are ASCII in practice; a lone surrogate is kept as its code).
            if (code < 0x80) {
              out += char(code);
            } else if (code < 0x800) {
              out += char(0xc0 | (code >> 6));
              out += char(0x80 | (code & 0x3f));
            } else {
              out += char(0xe0 | (code >> 12));
              out += char(0x80 | ((code >> 6) & 0x3f));
              out += char(0x80 | (code & 0x3f));
            }
            continue;
          }
          case '"': case '\\': case '/': break;
          default: fail("an unknown escape in a string");
        }
      }
      out += char(c);
      if (out.size() > kMaxString) fail("a string of more than 64 MiB");
    }
  }
  Node value(int depth) {
    if (depth > kMaxDepth) fail("values nested more than " + std::to_string(kMaxDepth) + " deep");
    const int c = after_space();
    count_node();
    Node n;
    if (c == '"') {
      n.kind = Node::Kind::String;
      n.text = string();
    } else if (c == '[') {
      get();
      list(n, depth);
    } else if (c == '{') {
      get();
      n.kind = Node::Kind::Map;
      if (after_space() == '}') {
        get();
        return n;
      }
      for (;;) {
        if (after_space() != '"') fail("a map key that is not a string");
        n.keys.push_back(string());
        expect(':');
        n.items.push_back(value(depth + 1));
        const int d = after_space();
        get();
        if (d == '}') break;
        if (d != ',') fail("',' or '}' expected in a map");
      }
    } else if (starts_number(c)) {
      n.kind = Node::Kind::Number;
      n.number = number();
    } else if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z')) {
      std::string word;
      while (word.size() < 16 && ((peek() >= 'a' && peek() <= 'z') || (peek() >= 'A' && peek() <= 'Z'))) word += char(get());
      if (word == "true" || word == "false") {
        n.kind = Node::Kind::Bool;
        n.number = word == "true";
      } else if (word != "null") {
        fail("'" + shown(word) + "' is not a JSON value (true, false, null; JSON has no NaN or infinity)");
      }
    } else {
      fail(c < 0 ? std::string("the file ends inside a value") : "an unexpected character");
    }
    return n;
  }
  void list(Node& n, int depth) {
    // Numbers first go to one array of doubles; a list that turns out to hold something else
    // has them as values after all.
    n.kind = Node::Kind::Uniform;
    n.type = kReal64;
    if (after_space() == ']') {
      get();
      return;
    }
    for (;;) {
      if (n.kind == Node::Kind::Uniform && starts_number(after_space())) {
        const double v = number();
        n.text.append(reinterpret_cast<const char*>(&v), 8);
        ++n.count;
      } else {
        if (n.kind == Node::Kind::Uniform) {
          for (uint64_t i = 0; i < n.count; ++i) {
            count_node();
            Node x;
            x.kind = Node::Kind::Number;
            std::memcpy(&x.number, n.text.data() + 8 * i, 8);
            n.items.push_back(x);
          }
          n.kind = Node::Kind::List;
          n.text.clear();
          n.count = 0;
        }
        n.items.push_back(value(depth + 1));
      }
      const int d = after_space();
      get();
      if (d == ']') return;
      if (d != ',') fail("',' or ']' expected in a list");
    }
  }

  DecompressedStream& in_;
  const std::string& path_;
  std::string pending_;
  size_t at_ = 0;
  int next_ = -1;
  uint64_t nodes_ = 0;
};

/// Reading the structure: lists of key/value pairs (the schema's usual form) or maps.
class Schema {
 public:
  Schema(const std::string& path, bool swap) : path_(path), swap_(swap) {}

  [[noreturn]] void fail(const std::string& problem) const { fail_in(path_, problem); }

  const Node* find(const Node& n, const char* key) const {
    if (n.kind == Node::Kind::Map) {
      for (size_t i = 0; i < n.keys.size(); ++i)
        if (n.keys[i] == key) return &n.items[i];
      return nullptr;
    }
    if (n.kind != Node::Kind::List) return nullptr;
    for (size_t i = 0; i + 1 < n.items.size(); i += 2)
      if (n.items[i].kind == Node::Kind::String && n.items[i].text == key) return &n.items[i + 1];
    return nullptr;
  }

  /// Elements of an array value (uniform, or a list of numbers and booleans).
  uint64_t size(const Node& n) const {
    if (n.kind == Node::Kind::Uniform) return n.count;
    if (n.kind == Node::Kind::List) return n.items.size();
    return 0;
  }
  bool is_array(const Node& n) const { return n.kind == Node::Kind::Uniform || n.kind == Node::Kind::List; }

  /// Element i of an array value, as a number; `what` names it in errors.
  double at(const Node& n, uint64_t i, const std::string& what) const {
    if (n.kind == Node::Kind::List) {
      const Node& e = n.items[size_t(i)];
      if (e.kind != Node::Kind::Number && e.kind != Node::Kind::Bool) fail(what + " holds a value that is not a number");
      return e.number;
    }
    const unsigned char* b = reinterpret_cast<const unsigned char*>(n.text.data());
    if (n.type == kBool) return double((word(b + 4 * (i / 32)) >> (i % 32)) & 1u);
    return number_at(n.type, b + i * element_bytes(n.type), swap_);
  }

  /// A non-negative integer value.
  uint64_t count(const Node& n, const std::string& what, uint64_t most) const {
    if (n.kind != Node::Kind::Number || !(n.number >= 0) || n.number != std::floor(n.number) || n.number > double(most))
      fail(what + " is not a count from 0 to " + std::to_string(most));
    return uint64_t(n.number);
  }

  /// The `elements` tuples of `width` numbers in `block` (an attribute's "values"), into
  /// out[element * width + component]. Three layouts, as hgeo.py reads them:
  ///  - "tuples": one array of `width` numbers per element;
  ///  - "arrays": `width` arrays of one number per element;
  ///  - "rawpagedata": the elements in pages of "pagesize"; each tuple split into the
  ///    sub-vectors that "packing" lists (default: one of `width`); the data page by page,
  ///    within a page sub-vector by sub-vector, each the page's elements' values in order -
  ///    or, where "constantpageflags" (per sub-vector, a flag per page) marks the page
  ///    constant, one sub-vector value for all of them.
  void decode(const Node& block, uint64_t elements, size_t width, std::vector<float>& out, const std::string& what) const {
    out.assign(size_t(elements) * width, 0.0f);
    if (const Node* tuples = find(block, "tuples")) {
      if (tuples->kind != Node::Kind::List || tuples->items.size() != elements)
        fail(what + ": \"tuples\" holds " + std::to_string(this->size(*tuples)) + " tuples for " + std::to_string(elements) + " points");
      for (uint64_t e = 0; e < elements; ++e) {
        const Node& t = tuples->items[size_t(e)];
        if (!is_array(t) || this->size(t) != width) fail(what + ": tuple " + std::to_string(e) + " does not hold " + std::to_string(width) + " values");
        for (size_t c = 0; c < width; ++c) out[size_t(e) * width + c] = float(at(t, c, what));
      }
      return;
    }
    if (const Node* arrays = find(block, "arrays")) {
      if (arrays->kind != Node::Kind::List || arrays->items.size() != width)
        fail(what + ": \"arrays\" does not hold " + std::to_string(width) + " arrays");
      for (size_t c = 0; c < width; ++c) {
        const Node& a = arrays->items[c];
        if (!is_array(a) || this->size(a) != elements)
          fail(what + ": array " + std::to_string(c) + " does not hold " + std::to_string(elements) + " values");
        for (uint64_t e = 0; e < elements; ++e) out[size_t(e) * width + c] = float(at(a, e, what));
      }
      return;
    }
    const Node* raw = find(block, "rawpagedata");
    if (raw == nullptr || !is_array(*raw)) fail(what + " has no \"tuples\", \"arrays\" or \"rawpagedata\" to read");
    const Node* page_node = find(block, "pagesize");
    if (page_node == nullptr) fail(what + ": \"rawpagedata\" without \"pagesize\"");
    const uint64_t page = count(*page_node, what + "'s \"pagesize\"", kMaxPageSize);
    if (page == 0) fail(what + "'s \"pagesize\" is 0");
    std::vector<size_t> packing;
    if (const Node* pk = find(block, "packing")) {
      if (!is_array(*pk)) fail(what + "'s \"packing\" is not an array");
      size_t sum = 0;
      for (uint64_t k = 0; k < this->size(*pk); ++k) {
        const double w = at(*pk, k, what + "'s \"packing\"");
        if (!(w >= 1 && w <= double(width) && w == std::floor(w))) fail(what + "'s \"packing\" holds " + std::to_string(w));
        packing.push_back(size_t(w));
        sum += size_t(w);
      }
      if (sum != width) fail(what + "'s \"packing\" adds up to " + std::to_string(sum) + ", not the tuple size " + std::to_string(width));
    } else {
      packing.push_back(width);
    }
    const uint64_t pages = (elements + page - 1) / page;
    const Node* flags = find(block, "constantpageflags");
    if (flags != nullptr && (flags->kind != Node::Kind::List || flags->items.size() != packing.size()))
      fail(what + "'s \"constantpageflags\" does not hold one array per packed sub-vector");
    for (size_t k = 0; flags != nullptr && k < packing.size(); ++k) {
      const Node& f = flags->items[k];
      if (!is_array(f) || (this->size(f) != 0 && this->size(f) != pages))
        fail(what + "'s \"constantpageflags\" for sub-vector " + std::to_string(k) + " does not hold one flag per page (" +
                std::to_string(pages) + ")");
    }
    const uint64_t stored = this->size(*raw);
    uint64_t at_raw = 0;
    for (uint64_t pg = 0; pg < pages; ++pg) {
      const uint64_t first = pg * page, m = std::min(page, elements - first);
      size_t c0 = 0;
      for (size_t k = 0; k < packing.size(); ++k) {
        const size_t w = packing[k];
        const Node* f = flags != nullptr ? &flags->items[k] : nullptr;
        const bool constant = f != nullptr && this->size(*f) != 0 && at(*f, pg, what) != 0;
        const uint64_t need = constant ? w : m * w;
        if (at_raw + need > stored) fail(what + ": \"rawpagedata\" holds " + std::to_string(stored) + " values, fewer than its pages need");
        for (uint64_t e = 0; e < m; ++e)
          for (size_t c = 0; c < w; ++c)
            out[size_t(first + e) * width + c0 + c] = float(at(*raw, at_raw + (constant ? c : e * w + c), what));
        at_raw += need;
        c0 += w;
      }
    }
    if (at_raw != stored)
      fail(what + ": \"rawpagedata\" holds " + std::to_string(stored) + " values, its pages " + std::to_string(at_raw));
  }

 private:
  uint32_t word(const unsigned char* b) const {
    unsigned char v[4] = {b[0], b[1], b[2], b[3]};
    if (swap_) std::reverse(v, v + 4);
    uint32_t w;
    std::memcpy(&w, v, 4);
    return w;
  }
  const std::string& path_;
  bool swap_;
};

/// The points of a parsed geometry document; `bytes` the stream's length, `swap` whether its
/// uniform arrays hold big-endian values.
FileContents geometry_of(const Node& root, const std::string& path, bool swap, uint64_t bytes) {
  const Schema s(path, swap);
  const Node* count_node = s.find(root, "pointcount");
  if (count_node == nullptr) s.fail("the geometry has no \"pointcount\" (not a Houdini geometry file?)");
  const uint64_t points = s.count(*count_node, "\"pointcount\"", uint64_t(UINT32_MAX) - 1);
  // Values carried, at most kValuesPerByte per byte the stream held (constant pages expand).
  const uint64_t budget = kValuesPerByte * bytes + (uint64_t(1) << 20);
  uint64_t carried = 0;
  FileContents out;
  bool have_positions = false;
  const Node* attributes = s.find(root, "attributes");
  const Node* point_attributes = attributes != nullptr ? s.find(*attributes, "pointattributes") : nullptr;
  if (point_attributes != nullptr && point_attributes->kind == Node::Kind::List) {
    for (const Node& entry : point_attributes->items) {
      if (entry.kind != Node::Kind::List || entry.items.size() != 2) s.fail("a point attribute entry is not [definition, values]");
      const Node* name_node = s.find(entry.items[0], "name");
      const Node* type_node = s.find(entry.items[0], "type");
      if (name_node == nullptr || name_node->kind != Node::Kind::String) s.fail("a point attribute without a name");
      const std::string name = name_node->text;
      const std::string what = "point attribute '" + shown(name) + "'";
      if (type_node == nullptr || type_node->kind != Node::Kind::String || type_node->text != "numeric") {
        // Strings, dictionaries: no per-particle number.
        const std::string type = type_node != nullptr && type_node->kind == Node::Kind::String ? type_node->text : "";
        const std::string kind = type == "string" ? "strings" : type.empty() ? "no type" : shown(type) + " values";
        note_not_read(out, what + " (" + kind + ")");
        continue;
      }
      const Node* values = s.find(entry.items[1], "values");
      if (values == nullptr) s.fail(what + " has no \"values\"");
      const Node* size_node = s.find(*values, "size");
      if (size_node == nullptr) size_node = s.find(entry.items[1], "size");
      const uint64_t size = size_node != nullptr ? s.count(*size_node, what + "'s tuple size", 65535) : 1;
      if (size == 0) continue;
      const bool position = name == "P" && !have_positions;
      if (position && size < 3) s.fail("point attribute 'P' has " + std::to_string(size) + " values per point, not 3");
      carried += points * size;
      if (carried > budget)
        s.fail("the point attributes would expand to " + std::to_string(carried) + " values from " +
                    std::to_string(bytes) + " bytes (more than " + std::to_string(kValuesPerByte) +
                    " per byte: not a plausible geometry file)");
      std::vector<float> v;
      s.decode(*values, points, size_t(size), v, what);
      if (position) {
        have_positions = true;
        out.positions.resize(size_t(points));
        for (size_t i = 0; i < points; ++i) out.positions[i] = {double(v[i * size]), double(v[i * size + 1]), double(v[i * size + 2])};
      } else if (name == "N" && size == 3 && out.normals.empty()) {
        out.normals.resize(size_t(points));
        for (size_t i = 0; i < points; ++i) out.normals[i] = {double(v[i * 3]), double(v[i * 3 + 1]), double(v[i * 3 + 2])};
      } else {
        out.attributes.push_back({unique_attribute_name(out, name), int(size), std::move(v)});
      }
    }
  }
  if (!have_positions) {
    if (points == 0) return out;
    s.fail("the geometry's " + std::to_string(points) + " points have no position attribute 'P'");
  }
  return out;
}

}  // namespace

FileContents read_bgeo_binary_json(DecompressedStream& in, const std::string& path, bool big_endian) {
  Parser parser(in, path, big_endian);
  const Node root = parser.parse_document();
  return geometry_of(root, path, big_endian, parser.bytes_read());
}

FileContents read_geo_text_json(DecompressedStream& in, const std::string& path, std::string_view read_already) {
  TextParser parser(in, path, read_already);
  const Node root = parser.parse_document();
  return geometry_of(root, path, false, parser.bytes_read());
}

}  // namespace particlemesh::detail
