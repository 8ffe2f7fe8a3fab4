// Stanford PLY reader: ascii, binary_little_endian and binary_big_endian. Reads x, y, z of the
// "vertex" element, the "vertex_indices"/"vertex_index" list of "face", and "tristrips";
// every other property and element is skipped by its declared type.

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "qs/io/detail_parse.h"

namespace qs::io::detail {

namespace {

enum class Scalar { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool scalar_from_name(std::string_view s, Scalar& t) {
  struct Entry {
    std::string_view name;
    Scalar type;
  };
  static constexpr Entry kTypes[] = {
      {"char", Scalar::Int8},       {"int8", Scalar::Int8},      {"uchar", Scalar::UInt8},
      {"uint8", Scalar::UInt8},     {"short", Scalar::Int16},    {"int16", Scalar::Int16},
      {"ushort", Scalar::UInt16},   {"uint16", Scalar::UInt16},  {"int", Scalar::Int32},
      {"int32", Scalar::Int32},     {"uint", Scalar::UInt32},    {"uint32", Scalar::UInt32},
      {"float", Scalar::Float32},   {"float32", Scalar::Float32}, {"double", Scalar::Float64},
      {"float64", Scalar::Float64}};
  for (const Entry& e : kTypes)
    if (e.name == s) {
      t = e.type;
      return true;
    }
  return false;
}

std::size_t scalar_size(Scalar t) {
  switch (t) {
    case Scalar::Int8:
    case Scalar::UInt8: return 1;
    case Scalar::Int16:
    case Scalar::UInt16: return 2;
    case Scalar::Int32:
    case Scalar::UInt32:
    case Scalar::Float32: return 4;
    case Scalar::Float64: return 8;
  }
  return 1;
}

bool is_float(Scalar t) { return t == Scalar::Float32 || t == Scalar::Float64; }

struct Property {
  std::string name;
  bool is_list = false;
  Scalar type = Scalar::Float32;        // the item type of a list
  Scalar count_type = Scalar::UInt8;    // lists only
};

struct Element {
  std::string name;
  long long count = 0;
  long long line = 0;  // header line, for messages
  std::vector<Property> props;
};

enum class Encoding { Ascii, BinaryLittle, BinaryBig };

const char kTypeList[] =
    "char uchar short ushort int uint float double (or int8 uint8 int16 uint16 int32 uint32 "
    "float32 float64)";

// ---- binary ----------------------------------------------------------------------------------

class BinaryCursor {
 public:
  BinaryCursor(std::string_view data, std::size_t pos, bool swap, const std::string& name)
      : data_(data), pos_(pos), swap_(swap), name_(name) {}

  std::size_t pos() const { return pos_; }
  std::size_t left() const { return data_.size() - pos_; }

  void need(std::size_t n, const Element& e, long long record) const {
    if (left() < n)
      fail_at_offset(name_, pos_,
                     "file ends inside " + e.name + " " + std::to_string(record) + " of " +
                         std::to_string(e.count) + " (needs " + std::to_string(n) +
                         " more bytes, " + std::to_string(left()) + " left); truncated file?");
  }
  void skip(std::size_t n) { pos_ += n; }

  /// Reads one scalar (bounds already checked by need()).
  double read(Scalar t) {
    unsigned char b[8];
    const std::size_t n = scalar_size(t);
    std::memcpy(b, data_.data() + pos_, n);
    pos_ += n;
    if (swap_)
      for (std::size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
    switch (t) {
      case Scalar::Int8: { std::int8_t v; std::memcpy(&v, b, 1); return v; }
      case Scalar::UInt8: { std::uint8_t v; std::memcpy(&v, b, 1); return v; }
      case Scalar::Int16: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
      case Scalar::UInt16: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
      case Scalar::Int32: { std::int32_t v; std::memcpy(&v, b, 4); return v; }
      case Scalar::UInt32: { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
      case Scalar::Float32: { float v; std::memcpy(&v, b, 4); return v; }
      case Scalar::Float64: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0;
  }

 private:
  std::string_view data_;
  std::size_t pos_;
  bool swap_;
  const std::string& name_;
};

// ---- ascii -----------------------------------------------------------------------------------

class TextCursor {
 public:
  TextCursor(std::string_view data, std::size_t pos, long long line)
      : data_(data), pos_(pos), line_(line) {}

  /// The next token (empty at the end); line() is its line.
  std::string_view next() {
    const std::size_t n = data_.size();
    while (pos_ < n && is_space(data_[pos_])) {
      if (data_[pos_] == '\n') ++line_;
      ++pos_;
    }
    const std::size_t start = pos_;
    while (pos_ < n && !is_space(data_[pos_])) ++pos_;
    return data_.substr(start, pos_ - start);
  }
  long long line() const { return line_; }

 private:
  std::string_view data_;
  std::size_t pos_;
  long long line_;
};

// ---- the element loop, shared by both encodings ----------------------------------------------

/// What to do with one element.
struct Roles {
  enum class Kind { Vertex, Face, Strips, Other } kind = Kind::Other;
  int x = -1, y = -1, z = -1;  // vertex property indices
  int list = -1;               // face / strip index list
};

/// A source of values: binary or text, with one interface for the element loop.
class Source {
 public:
  virtual ~Source() = default;
  virtual double scalar(const Element& e, const Property& p, long long record) = 0;
  virtual long long integer(const Element& e, const Property& p, Scalar t, long long record) = 0;
  /// Skips `n` list items of type t (binary: by size, bounds checked).
  virtual void skip_items(const Element& e, const Property& p, long long n, long long record) = 0;
  [[noreturn]] virtual void fail_here(const std::string& message) = 0;
};

class BinarySource final : public Source {
 public:
  BinarySource(BinaryCursor& c, const std::string& name) : c_(c), name_(name) {}
  double scalar(const Element& e, const Property& p, long long record) override {
    c_.need(scalar_size(p.type), e, record);
    return c_.read(p.type);
  }
  long long integer(const Element& e, const Property& p, Scalar t, long long record) override {
    start_ = c_.pos();
    c_.need(scalar_size(t), e, record);
    const double v = c_.read(t);
    if (is_float(t) && (!std::isfinite(v) || v != std::floor(v) || std::fabs(v) > 2147483647.0))
      fail_at_offset(name_, start_,
                     "property " + quote(p.name) + " of " + e.name + " " + std::to_string(record) +
                         " is not an integer");
    return static_cast<long long>(v);
  }
  void skip_items(const Element& e, const Property& p, long long n, long long record) override {
    const std::size_t bytes = static_cast<std::size_t>(n) * scalar_size(p.type);
    c_.need(bytes, e, record);
    c_.skip(bytes);
  }
  void fail_here(const std::string& message) override { fail_at_offset(name_, start_, message); }
  void mark() { start_ = c_.pos(); }

 private:
  BinaryCursor& c_;
  const std::string& name_;
  std::size_t start_ = 0;
};

class TextSource final : public Source {
 public:
  TextSource(TextCursor& c, const std::string& name) : c_(c), name_(name) {}
  double scalar(const Element& e, const Property& p, long long record) override {
    const std::string_view tok = token(e, p, record);
    double v = 0;
    if (!parse_double(tok, v))
      fail_at_line(name_, c_.line(),
                   "property " + quote(p.name) + " of " + e.name + " " + std::to_string(record) +
                       ": " + quote(tok) + " is not a number");
    return v;
  }
  long long integer(const Element& e, const Property& p, Scalar, long long record) override {
    const std::string_view tok = token(e, p, record);
    long long v = 0;
    double d = 0;
    if (parse_int(tok, v)) return v;
    if (parse_double(tok, d) && std::isfinite(d) && d == std::floor(d) && std::fabs(d) <= 2147483647.0)
      return static_cast<long long>(d);
    fail_at_line(name_, c_.line(),
                   "property " + quote(p.name) + " of " + e.name + " " + std::to_string(record) +
                       ": " + quote(tok) + " is not an integer");
  }
  void skip_items(const Element& e, const Property& p, long long n, long long record) override {
    for (long long i = 0; i < n; ++i) token(e, p, record);
  }
  void fail_here(const std::string& message) override { fail_at_line(name_, c_.line(), message); }

 private:
  std::string_view token(const Element& e, const Property& p, long long record) {
    const std::string_view tok = c_.next();
    if (tok.empty())
      fail_at_line(name_, c_.line(),
                   "file ends inside " + e.name + " " + std::to_string(record) + " of " +
                       std::to_string(e.count) + " (expected property " + quote(p.name) +
                       "); truncated file, or the header counts are wrong");
    return tok;
  }
  TextCursor& c_;
  const std::string& name_;
};

std::string plural(const Element& e) {
  if (e.name == "vertex") return "vertices";
  if (e.name == "face") return "faces";
  return quote(e.name) + " elements";
}

}  // namespace

ReadResult read_ply(std::string_view data, const std::string& name) {
  ReadResult result;
  auto& positions = result.mesh.positions;
  auto& faces = result.mesh.faces;

  // ---- header ----
  LineReader lines(data);
  std::string_view line;
  lines.next(line);
  if (trim(line) != "ply")
    fail_at_line(name, 1, "expected 'ply' on the first line, found " + quote(trim(line)) +
                              "; this is not a PLY file");
  Encoding encoding = Encoding::Ascii;
  bool have_format = false, have_end = false;
  std::vector<Element> elements;
  while (!have_end && lines.next(line)) {
    std::string_view rest = line;
    const std::string_view key = next_token(rest);
    if (key.empty() || key == "comment" || key == "obj_info") continue;
    if (key == "format") {
      const std::string_view f = next_token(rest);
      if (f == "ascii") encoding = Encoding::Ascii;
      else if (f == "binary_little_endian") encoding = Encoding::BinaryLittle;
      else if (f == "binary_big_endian") encoding = Encoding::BinaryBig;
      else
        fail_at_line(name, lines.line(),
                     "unknown PLY format " + quote(f) +
                         "; expected ascii, binary_little_endian or binary_big_endian");
      have_format = true;
    } else if (key == "element") {
      Element e;
      e.name = std::string(next_token(rest));
      const std::string_view count = next_token(rest);
      if (e.name.empty() || !parse_int(count, e.count))
        fail_at_line(name, lines.line(), "expected 'element <name> <count>', found " + quote(trim(line)));
      if (e.count < 0)
        fail_at_line(name, lines.line(),
                     "negative count " + std::to_string(e.count) + " for element " + quote(e.name));
      e.line = lines.line();
      elements.push_back(std::move(e));
    } else if (key == "property") {
      if (elements.empty())
        fail_at_line(name, lines.line(), "property declared before any element");
      Property p;
      std::string_view type = next_token(rest);
      if (type == "list") {
        p.is_list = true;
        const std::string_view ctype = next_token(rest);
        if (!scalar_from_name(ctype, p.count_type))
          fail_at_line(name, lines.line(), "unknown list count type " + quote(ctype) + "; expected " + kTypeList);
        if (is_float(p.count_type))
          fail_at_line(name, lines.line(), "list count type " + quote(ctype) + " must be an integer type");
        type = next_token(rest);
      }
      if (!scalar_from_name(type, p.type))
        fail_at_line(name, lines.line(), "unknown property type " + quote(type) + "; expected " + kTypeList);
      p.name = std::string(next_token(rest));
      if (p.name.empty()) fail_at_line(name, lines.line(), "property without a name");
      elements.back().props.push_back(std::move(p));
    } else if (key == "end_header") {
      have_end = true;
    } else {
      fail_at_line(name, lines.line(),
                   "unknown PLY header line " + quote(trim(line)) +
                       "; expected format, element, property, comment, obj_info or end_header");
    }
  }
  if (!have_end)
    fail(name, "no 'end_header' line; the PLY header is incomplete (truncated file?)");
  if (!have_format) fail_at_line(name, 2, "missing 'format' line in the PLY header");
  result.report.variant = encoding == Encoding::Ascii          ? "ascii"
                          : encoding == Encoding::BinaryLittle ? "binary_little_endian"
                                                               : "binary_big_endian";

  // ---- roles, and counts against the bytes left (before reserving anything) ----
  std::vector<Roles> roles(elements.size());
  long long nv = -1;
  std::size_t budget = lines.bytes_left();
  for (std::size_t i = 0; i < elements.size(); ++i) {
    const Element& e = elements[i];
    Roles& r = roles[i];
    for (int k = 0; k < static_cast<int>(e.props.size()); ++k) {
      const std::string& pn = e.props[static_cast<std::size_t>(k)].name;
      if (pn == "x") r.x = k;
      if (pn == "y") r.y = k;
      if (pn == "z") r.z = k;
      if (pn == "vertex_indices" || pn == "vertex_index") r.list = k;
    }
    const std::string where = name + ":" + std::to_string(e.line);
    if (e.name == "vertex") {
      if (nv >= 0) throw InvalidInput(where + ": a second 'vertex' element; expected one");
      if (r.x < 0 || r.y < 0 || r.z < 0)
        throw InvalidInput(where + ": element vertex lacks one of the properties x, y, z");
      for (int k : {r.x, r.y, r.z})
        if (e.props[static_cast<std::size_t>(k)].is_list)
          throw InvalidInput(where + ": vertex property " + quote(e.props[static_cast<std::size_t>(k)].name) +
                             " is a list; expected a scalar");
      r.kind = Roles::Kind::Vertex;
      nv = e.count;
    } else if (e.name == "face" || e.name == "tristrips") {
      if (r.list < 0 || !e.props[static_cast<std::size_t>(r.list)].is_list)
        throw InvalidInput(where + ": element " + e.name +
                           " has no list property 'vertex_indices' (or 'vertex_index')");
      if (is_float(e.props[static_cast<std::size_t>(r.list)].type))
        result.report.notes.push_back("vertex indices are stored as floating-point numbers");
      r.kind = e.name == "face" ? Roles::Kind::Face : Roles::Kind::Strips;
    }
    std::size_t min_bytes = 0;
    for (const Property& p : e.props)
      min_bytes += encoding == Encoding::Ascii ? 2
                   : p.is_list                 ? scalar_size(p.count_type)
                                               : scalar_size(p.type);
    if (!e.props.empty()) check_count_fits(where, e.count, plural(e).c_str(), min_bytes, budget);
    if (min_bytes > 0) budget -= std::min(budget, static_cast<std::size_t>(e.count) * min_bytes);
  }
  if (nv < 0) nv = 0;
  for (std::size_t i = 0; i < elements.size(); ++i)
    if (roles[i].kind != Roles::Kind::Other && roles[i].kind != Roles::Kind::Vertex && nv == 0 &&
        elements[i].count > 0)
      fail_at_line(name, elements[i].line, "element " + elements[i].name + " has entries but the file has no vertices");
  positions.reserve(static_cast<std::size_t>(nv));
  for (std::size_t i = 0; i < elements.size(); ++i)
    if (roles[i].kind == Roles::Kind::Face) faces.reserve(faces.size() + static_cast<std::size_t>(elements[i].count));

  // ---- body ----
  BinaryCursor bin(data, lines.offset(),
                   (encoding == Encoding::BinaryLittle) != (std::endian::native == std::endian::little),
                   name);
  TextCursor text(data, lines.offset(), lines.line() + 1);
  BinarySource bsrc(bin, name);
  TextSource tsrc(text, name);
  Source& src = encoding == Encoding::Ascii ? static_cast<Source&>(tsrc) : bsrc;

  std::vector<int> corners;
  long long strip_degenerate = 0;
  for (std::size_t i = 0; i < elements.size(); ++i) {
    const Element& e = elements[i];
    const Roles& r = roles[i];
    if (e.props.empty()) continue;
    if (encoding != Encoding::Ascii && r.kind == Roles::Kind::Other) {
      bool fixed = true;
      std::size_t size = 0;
      for (const Property& p : e.props) {
        fixed = fixed && !p.is_list;
        size += scalar_size(p.type);
      }
      if (fixed) {  // skip the whole element at once
        bin.need(static_cast<std::size_t>(e.count) * size, e, 0);
        bin.skip(static_cast<std::size_t>(e.count) * size);
        continue;
      }
    }
    for (long long rec = 0; rec < e.count; ++rec) {
      double xyz[3] = {0, 0, 0};
      for (int k = 0; k < static_cast<int>(e.props.size()); ++k) {
        const Property& p = e.props[static_cast<std::size_t>(k)];
        if (!p.is_list) {
          const double v = src.scalar(e, p, rec);
          if (r.kind == Roles::Kind::Vertex) {
            if (k == r.x) xyz[0] = v;
            if (k == r.y) xyz[1] = v;
            if (k == r.z) xyz[2] = v;
          }
          continue;
        }
        bsrc.mark();
        const long long n = src.integer(e, p, p.count_type, rec);
        if (n < 0)
          src.fail_here("negative list length " + std::to_string(n) + " in property " + quote(p.name) +
                        " of " + e.name + " " + std::to_string(rec));
        // Only face and tristrips elements hold faces: an "edge" (or any other) element's
        // vertex_indices list is skipped like any other property.
        if (k != r.list || r.kind == Roles::Kind::Other) {
          src.skip_items(e, p, n, rec);
          continue;
        }
        if (encoding != Encoding::Ascii) bin.need(static_cast<std::size_t>(n) * scalar_size(p.type), e, rec);
        corners.clear();
        for (long long c = 0; c < n; ++c) {
          bsrc.mark();
          const long long id = src.integer(e, p, p.type, rec);
          if (r.kind == Roles::Kind::Strips && id == -1) {
            corners.push_back(-1);
            continue;
          }
          if (id < 0 || id >= nv)
            src.fail_here(e.name + " " + std::to_string(rec) + " references vertex " + std::to_string(id) +
                          " but the file has " + std::to_string(nv) + " vertices (0-based ids 0.." +
                          std::to_string(nv - 1) + ")");
          corners.push_back(static_cast<int>(id));
        }
        if (r.kind == Roles::Kind::Face) {
          add_polygon(faces, corners.data(), corners.size(), result.report);
        } else {  // triangle strips: -1 restarts, every other triangle flipped
          std::size_t start = 0;
          for (std::size_t j = 0; j <= corners.size(); ++j) {
            if (j < corners.size() && corners[j] != -1) {
              if (j - start >= 2) {
                const int a = corners[j - 2], b = corners[j - 1], c = corners[j];
                if (a == b || b == c || a == c) {
                  ++strip_degenerate;
                } else if ((j - start) % 2 == 0) {
                  faces.push_back({a, b, c});
                } else {
                  faces.push_back({b, a, c});
                }
              }
            } else {
              start = j + 1;
            }
          }
        }
      }
      if (r.kind == Roles::Kind::Vertex) positions.emplace_back(xyz[0], xyz[1], xyz[2]);
    }
  }

  if (encoding == Encoding::Ascii) {
    const std::string_view extra = text.next();
    if (!extra.empty())
      fail_at_line(name, text.line(),
                   "unexpected data " + quote(extra) +
                       " after the last element; the element counts in the header do not match the data");
  } else if (bin.left() > 0) {
    result.report.notes.push_back("ignored " + std::to_string(bin.left()) +
                                  " bytes after the last element");
  }
  if (strip_degenerate > 0)
    result.report.notes.push_back("skipped " + std::to_string(strip_degenerate) +
                                  " degenerate triangles of triangle strips (strip joins)");
  return result;
}

}  // namespace qs::io::detail
