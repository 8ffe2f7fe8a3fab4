#pragma once
// Reading qs's JSON inputs (landmarks, dissection.json, remesh.json) as hostile text: a nesting
// limit, duplicate keys refused, numbers checked for type, range and finiteness, and messages
// that never embed megabytes of the document or bytes that are not UTF-8.
//
// Header-only because it needs nlohmann::json: include it only from modules that link
// nlohmann_json (landmarks, dissect, remesh), never from a public header.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "qs/core/error.h"

namespace qs::json_strict {

/// Deepest nesting of arrays and objects accepted (qs's own files nest at most 5 deep).
inline constexpr int kMaxDepth = 64;

/// `s` with every byte that is not part of valid UTF-8, and every control character, written as
/// \xNN, cut to `max_bytes` (with "..." when cut): safe to put in a message or a JSON string.
inline std::string printable(std::string_view s, std::size_t max_bytes = 200) {
  std::string out;
  std::size_t i = 0;
  auto hex = [&](unsigned char c) {
    static const char* d = "0123456789abcdef";
    out += "\\x";
    out += d[c >> 4];
    out += d[c & 15];
  };
  while (i < s.size()) {
    if (out.size() >= max_bytes) {
      out += "...";
      break;
    }
    const unsigned char c = static_cast<unsigned char>(s[i]);
    int len = 0;
    std::uint32_t cp = 0;
    if (c < 0x80) len = 1, cp = c;
    else if ((c & 0xE0) == 0xC0) len = 2, cp = c & 0x1F;
    else if ((c & 0xF0) == 0xE0) len = 3, cp = c & 0x0F;
    else if ((c & 0xF8) == 0xF0) len = 4, cp = c & 0x07;
    bool ok = len > 0 && i + len <= s.size();
    for (int k = 1; ok && k < len; ++k) {
      const unsigned char cc = static_cast<unsigned char>(s[i + k]);
      ok = (cc & 0xC0) == 0x80;
      cp = (cp << 6) | (cc & 0x3F);
    }
    // Overlong forms, surrogates and code points past U+10FFFF are not UTF-8 either.
    if (ok && ((len == 2 && cp < 0x80) || (len == 3 && cp < 0x800) || (len == 4 && cp < 0x10000) ||
               (cp >= 0xD800 && cp <= 0xDFFF) || cp > 0x10FFFF))
      ok = false;
    if (!ok) {
      hex(c);
      ++i;
    } else if (len == 1 && (c < 0x20 || c == 0x7F)) {
      hex(c);
      ++i;
    } else {
      out.append(s.substr(i, len));
      i += len;
    }
  }
  return out;
}

/// True if `s` is valid UTF-8 without control characters (what printable() leaves unchanged).
inline bool is_clean_text(std::string_view s) { return printable(s, std::string_view::npos) == s; }

/// The whole content of a regular file. \throws IoError naming the file when it is missing, a
/// folder, or unreadable; `what` says what the file should be ("remesh file", ...).
inline std::string read_text_file(const std::filesystem::path& path, const std::string& what) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(st))
    throw IoError(printable(path.string()) + ": cannot open: no such file; expected a " + what);
  if (std::filesystem::is_directory(st))
    throw IoError(printable(path.string()) + ": cannot open: is a folder, expected a " + what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(printable(path.string()) + ": cannot open the " + what);
  std::ostringstream buf;
  buf << in.rdbuf();
  if (in.bad()) throw IoError(printable(path.string()) + ": read error in the " + what);
  return buf.str();
}

/// Parses `text` as JSON. \throws InvalidInput naming `name` for a syntax error (with its byte
/// offset), nesting deeper than kMaxDepth, or an object with a repeated key.
inline nlohmann::json parse(std::string_view text, const std::string& name) {
  // Nesting is checked before parsing (outside strings), so that no deep document is ever built.
  {
    int depth = 0;
    bool in_string = false, escaped = false;
    for (std::size_t i = 0; i < text.size(); ++i) {
      const char c = text[i];
      if (in_string) {
        if (escaped) escaped = false;
        else if (c == '\\') escaped = true;
        else if (c == '"') in_string = false;
      } else if (c == '"') {
        in_string = true;
      } else if (c == '[' || c == '{') {
        if (++depth > kMaxDepth)
          throw InvalidInput(name + ": JSON nested more than " + std::to_string(kMaxDepth) + " levels deep (at byte " +
                             std::to_string(i) + ")");
      } else if (c == ']' || c == '}') {
        --depth;
      }
    }
  }
  std::vector<std::set<std::string>> keys;  // one set per open object
  std::string duplicate;
  const nlohmann::json::parser_callback_t cb = [&](int, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    using E = nlohmann::json::parse_event_t;
    if (event == E::object_start) keys.emplace_back();
    else if (event == E::object_end) {
      if (!keys.empty()) keys.pop_back();
    } else if (event == E::key && !keys.empty() && duplicate.empty() && parsed.is_string()) {
      if (!keys.back().insert(parsed.get_ref<const std::string&>()).second)
        duplicate = parsed.get_ref<const std::string&>();
    }
    return true;
  };
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(text.begin(), text.end(), cb);
  } catch (const nlohmann::json::parse_error& e) {
    // e.what() quotes the offending token, which may hold any bytes: make it printable.
    throw InvalidInput(name + ": not valid JSON at byte " + std::to_string(e.byte) + ": " + printable(e.what()));
  } catch (const nlohmann::json::exception& e) {
    throw InvalidInput(name + ": not valid JSON: " + printable(e.what()));
  }
  if (!duplicate.empty())
    throw InvalidInput(name + ": the key \"" + printable(duplicate) +
                       "\" appears twice in one object; every key must be unique");
  return doc;
}

/// A short description of a JSON value for a message: its type, and for a scalar its text
/// (never the dump of a large array or object).
inline std::string describe(const nlohmann::json& j) {
  if (j.is_object()) return "an object with " + std::to_string(j.size()) + " keys";
  if (j.is_array()) return "an array of " + std::to_string(j.size()) + " values";
  if (j.is_string()) return "the string \"" + printable(j.get_ref<const std::string&>(), 60) + "\"";
  return printable(j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), 60);
}

/// The integer value of `j` if it is an integer in [lo, hi] (JSON integers only: 3.0 is not
/// one); false otherwise, without undefined conversions.
inline bool integer_in(const nlohmann::json& j, long long lo, long long hi, long long& out) {
  if (j.is_number_unsigned()) {
    const auto u = j.get<std::uint64_t>();
    if (u > static_cast<std::uint64_t>(std::numeric_limits<long long>::max())) return false;
    out = static_cast<long long>(u);
  } else if (j.is_number_integer()) {
    out = j.get<long long>();
  } else {
    return false;
  }
  return out >= lo && out <= hi;
}

/// The value of `j` if it is a finite number (integers included).
inline bool finite_number(const nlohmann::json& j, double& out) {
  if (!j.is_number()) return false;
  out = j.get<double>();
  return std::isfinite(out);
}

/// dump() that never throws on strings that are not UTF-8 (they were checked on input; this is
/// the last guard): invalid bytes become U+FFFD.
template <class Json>
std::string dump(const Json& j, int indent) {
  return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace qs::json_strict
