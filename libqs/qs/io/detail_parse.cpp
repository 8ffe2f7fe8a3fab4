#include "qs/io/detail_parse.h"

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <limits>
#include <system_error>

namespace qs::io::detail {

void fail(const std::string& name, const std::string& message) {
  throw InvalidInput(name + ": " + message);
}

void fail_at_line(const std::string& name, long long line, const std::string& message) {
  throw InvalidInput(name + ":" + std::to_string(line) + ": " + message);
}

void fail_at_offset(const std::string& name, std::size_t offset, const std::string& message) {
  throw InvalidInput(name + ": byte offset " + std::to_string(offset) + ": " + message);
}

std::string quote(std::string_view token) {
  constexpr std::size_t kMax = 40;
  std::string out = "'";
  const std::size_t n = std::min(token.size(), kMax);
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(token[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      static const char* hex = "0123456789abcdef";
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  if (token.size() > kMax) out += "...";
  out += "'";
  return out;
}

long long line_of_offset(std::string_view data, std::size_t offset) {
  offset = std::min(offset, data.size());
  return 1 + static_cast<long long>(std::count(data.begin(), data.begin() + static_cast<std::ptrdiff_t>(offset), '\n'));
}

void require_text(std::string_view data, const std::string& name, const char* format) {
  const void* nul = std::memchr(data.data(), '\0', data.size());
  if (!nul) return;
  const auto offset = static_cast<std::size_t>(static_cast<const char*>(nul) - data.data());
  fail_at_line(name, line_of_offset(data, offset),
               "unexpected binary data (NUL byte at byte offset " + std::to_string(offset) +
                   "); expected a text " + format + " file");
}

bool parse_double(std::string_view token, double& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* first = token.data();
  const char* last = first + token.size();
  const auto [ptr, ec] = std::from_chars(first, last, value);
  if (ptr != last) return false;
  if (ec == std::errc()) return true;
  if (ec != std::errc::result_out_of_range) return false;
  // Overflow or underflow: take what strtod gives (+-HUGE_VAL = inf, or a denormal / zero).
  const std::string copy(token);
  value = std::strtod(copy.c_str(), nullptr);
  return true;
}

bool parse_int(std::string_view token, long long& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* first = token.data();
  const char* last = first + token.size();
  const auto [ptr, ec] = std::from_chars(first, last, value);
  return ec == std::errc() && ptr == last;
}

void check_count_fits(const std::string& where, long long count, const char* what,
                      std::size_t min_bytes, std::size_t bytes_left) {
  if (count < 0)
    throw InvalidInput(where + ": negative " + what + " count " + std::to_string(count));
  if (count > std::numeric_limits<int>::max())
    throw InvalidInput(where + ": header claims " + std::to_string(count) + " " + what +
                       "; qs supports at most " +
                       std::to_string(std::numeric_limits<int>::max()));
  if (min_bytes == 0) return;
  if (static_cast<unsigned long long>(count) > bytes_left / min_bytes + 1)
    throw InvalidInput(where + ": header claims " + std::to_string(count) + " " + what +
                       " but the file has only " + std::to_string(bytes_left) +
                       " bytes left (each needs at least " + std::to_string(min_bytes) +
                       "); the file is truncated or the header is wrong");
}

}  // namespace qs::io::detail
